//! Project tasks for QSA Strings, run as `cargo xtask <task>`.
//!
//! - `render`: render a scene file offline to a WAV (and a CSV of per-sample signals) and print a
//!   one-line JSON summary. See [`render`].
//! - `bench`: real-time factors of whole voices, one JSON line per case. See [`bench`].
//! - `report`: the error-against-run-time and stability report in `docs/report/`, or with
//!   `--quick` the CI check of its error figures. See [`report`].
//! - `presets`: list the factory presets (id, category, name, description). See [`presets`].
//! - `examples`: render one example per preset category into `docs/examples/` (WAV, spectrogram
//!   PNG and a README table). See [`examples`].
//! - `loudness`: loudness per key across the keyboard (EBU R128) and the voicing table. See
//!   [`loudness`].
//!
//! The tasks are a library so the test harness can run them in-process.

pub mod bench;
pub mod examples;
pub mod loudness;
pub mod presets;
pub mod render;
pub mod report;

use std::ffi::OsString;
use std::io::Write;

use clap::Parser;

/// The command line.
#[derive(Debug, Parser)]
#[command(name = "cargo xtask", about = "QSA Strings project tasks", version)]
pub enum Cli {
    /// Render a scene file offline: WAV, optional CSV, and a JSON summary line on stdout.
    Render(render::RenderArgs),
    /// Measure the real-time factor of whole voices: one JSON line per case.
    Bench(bench::BenchArgs),
    /// Run the error-against-run-time and stability sweeps and write docs/report/ (or, with
    /// --quick, check the committed error figures against fresh runs).
    Report(report::ReportArgs),
    /// Measure the piano's loudness per key (EBU R128) at three velocities and its fortissimo
    /// chords; write the report's loudness plot or re-voice the keyboard.
    Loudness(loudness::LoudnessArgs),
    /// List the factory presets: id, category, name and description.
    Presets,
    /// Render an audio example and spectrogram per preset category into docs/examples/.
    Examples(examples::ExamplesArgs),
}

/// Run the command line `args` (without the program name), writing the task's report to
/// `stdout`. Returns the process exit code.
pub fn run(args: impl IntoIterator<Item = OsString>, stdout: &mut dyn Write, stderr: &mut dyn Write) -> i32 {
    let cli = match Cli::try_parse_from(std::iter::once(OsString::from("xtask")).chain(args)) {
        Ok(cli) => cli,
        Err(e) => {
            let _ = write!(stderr, "{}", e.render().ansi());
            return e.exit_code();
        }
    };
    let result = match cli {
        Cli::Render(args) => render::run(&args, stdout).map(|_| ()).map_err(|e| e.to_string()),
        Cli::Bench(args) => bench::run(&args, stdout).map(|_| ()).map_err(|e| e.to_string()),
        Cli::Report(args) => report::run(&args, stdout).map_err(|e| e.to_string()),
        Cli::Presets => presets::run(stdout).map_err(|e| e.to_string()),
        Cli::Examples(args) => examples::run(&args, stdout).map(|_| ()).map_err(|e| e.to_string()),
        Cli::Loudness(args) => loudness::run(&args, stdout),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            let _ = writeln!(stderr, "error: {e}");
            1
        }
    }
}
