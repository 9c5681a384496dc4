//! Project tasks for QSA Strings, run as `cargo xtask <task>`.
//!
//! - `render`: render a scene file offline to a WAV (and a CSV of per-sample signals) and print a
//!   one-line JSON summary. See [`render`].
//! - `bench`: real-time factors of whole voices, one JSON line per case. See [`bench`](mod@bench).
//! - `report`: the error-against-run-time and stability report in `docs/report/`, or with
//!   `--quick` the CI check of its error figures. See [`report`].
//! - `presets`: list the factory presets (id, category, name, description), and write them as
//!   VST3 preset files. See [`presets`].
//! - `examples`: render one example per preset category into `docs/examples/` (WAV, spectrogram
//!   PNG and a README table). See [`examples`].
//! - `loudness`: loudness per key across the keyboard (EBU R128) and the voicing table. See
//!   [`loudness`].
//! - `bundle`, `bundle-universal`, `known-packages`: nice-plug's bundler (plugin bundles in
//!   `target/bundled/`, names from `bundler.toml`).
//! - `test`: every test, after the Python environment and the plugin bundles the real-host tests
//!   need. See [`test_suite`].
//!
//! The tasks are a library so the test harness can run them in-process.

pub mod bench;
pub mod examples;
pub mod folder;
pub mod loudness;
pub mod presets;
pub mod python_venv;
pub mod realism;
pub mod render;
pub mod report;
pub mod test_suite;

use std::ffi::OsString;
use std::io::{IsTerminal, Write};

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
    /// Compare the piano with measured grands: two-stage decay, contact duration, inharmonicity
    /// and decay rates against key, and a scale at three dynamics, into docs/report/realism.md.
    Realism(realism::RealismArgs),
    /// List the factory presets: id, category, name and description; with --vst3 DIR also write
    /// them as VST3 preset files for a host's preset browser.
    Presets(presets::PresetsArgs),
    /// Render an audio example and spectrogram per preset category into docs/examples/.
    Examples(examples::ExamplesArgs),
    /// Build plugin bundles (CLAP, VST3) into target/bundled/ with nice-plug's bundler.
    ///
    /// For example `cargo xtask bundle qsa-plugin --release`. The bundle names come from
    /// bundler.toml.
    Bundle(BundlerArgs),
    /// Build universal (x86_64 and aarch64) macOS plugin bundles with nice-plug's bundler.
    BundleUniversal(BundlerArgs),
    /// List the workspace packages nice-plug's bundler can bundle.
    KnownPackages,
    /// Run every test, with the plugin in real hosts.
    ///
    /// 1. Makes the Python virtual environment of the VST3 host test (target/python-venv/:
    ///    pedalboard, mido, numpy, pytest), only where something is missing.
    /// 2. Builds the allocation-checked debug bundle (copied to target/bundled-debug/) and the
    ///    release bundle (target/bundled/) the host tests load.
    /// 3. Runs `cargo test --workspace --profile test-release` (release optimisation with debug
    ///    assertions and overflow checks) with any arguments given.
    #[command(verbatim_doc_comment)]
    Test(test_suite::TestArgs),
}

/// Arguments of the bundler's commands, passed on to nice-plug's bundler.
#[derive(Debug, clap::Args)]
pub struct BundlerArgs {
    /// The package to bundle (or `-p PACKAGE` once per package), then any `cargo build` options
    /// (`--release`, `--profile NAME`, `--features ...`, `--target TRIPLE`).
    #[arg(trailing_var_arg = true, allow_hyphen_values = true, value_name = "PACKAGE_AND_CARGO_BUILD_ARGS")]
    pub args: Vec<String>,
}

/// Run the command line `args` (without the program name), writing the task's report to
/// `stdout`. Returns the process exit code: 0, 1 for a task that failed, 2 for options that do
/// not go together (as for the parser's own usage errors).
pub fn run(args: impl IntoIterator<Item = OsString>, stdout: &mut dyn Write, stderr: &mut dyn Write) -> i32 {
    let cli = match Cli::try_parse_from(std::iter::once(OsString::from("cargo xtask")).chain(args)) {
        Ok(cli) => cli,
        Err(e) => {
            // Help and version go to stdout, usage errors to stderr; styled only on a terminal.
            let terminal =
                if e.use_stderr() { std::io::stderr().is_terminal() } else { std::io::stdout().is_terminal() };
            let rendered = if terminal { e.render().ansi().to_string() } else { e.render().to_string() };
            let _ = if e.use_stderr() {
                stderr.write_all(rendered.as_bytes())
            } else {
                stdout.write_all(rendered.as_bytes())
            };
            return e.exit_code();
        }
    };
    let result = match cli {
        Cli::Render(args) => match render::run(&args, stdout) {
            Err(e @ render::RenderError::Usage(_)) => {
                let _ = writeln!(stderr, "error: {e}");
                return 2;
            }
            result => result.map(|_| ()).map_err(|e| e.to_string()),
        },
        Cli::Bench(args) => bench::run(&args, stdout).map(|_| ()).map_err(|e| e.to_string()),
        Cli::Report(args) => report::run(&args, stdout).map_err(|e| e.to_string()),
        Cli::Presets(args) => presets::run(&args, stdout),
        Cli::Examples(args) => examples::run(&args, stdout).map(|_| ()).map_err(|e| e.to_string()),
        Cli::Loudness(args) => loudness::run(&args, stdout),
        Cli::Realism(args) => realism::run(&args, stdout),
        Cli::Bundle(args) => bundler("bundle", args.args),
        Cli::BundleUniversal(args) => bundler("bundle-universal", args.args),
        Cli::KnownPackages => bundler("known-packages", Vec::new()),
        Cli::Test(args) => test_suite::run(&args),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            let _ = writeln!(stderr, "error: {e}");
            1
        }
    }
}

/// Run nice-plug's bundler `command` with `args`.
fn bundler(command: &str, args: Vec<String>) -> Result<(), String> {
    let args = std::iter::once(command.to_owned()).chain(args);
    nice_plug_xtask::main_with_args("cargo xtask", args).map_err(|e| format!("{e:#}"))
}
