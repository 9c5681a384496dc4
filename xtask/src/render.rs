//! `cargo xtask render <scene.toml> [--out PATH.wav] [--csv] [--chunk N]`
//! `cargo xtask render --midi FILE.mid [--preset NAME] [--mode piano|slide] [--set ID=VALUE ...] [--rate HZ] [--tail S] [--out PATH.wav]`
//!
//! With `--midi` the file plays through the instrument engine as the plugin would (see [`midi`]):
//! a stereo 32-bit float WAV, not normalised, and the same summary line, with `scene = "midi"`,
//! `contacts` = notes played, and `null` for what a MIDI render does not measure. The parameters
//! start from the defaults or from a factory preset (`--preset`), then `--mode` and `--set` apply.
//!
//! Renders a scene file through the dsp engine (built by [`qsa_dsp::scene_file::build()`], timed
//! here) and
//! - writes a mono 32-bit float WAV (default: next to the scene file, with extension `.wav`),
//!   peak-normalised unless the scene's `[output] normalize = false`;
//! - with `--csv`, writes the per-sample signals next to the WAV (same name, `.csv`), header
//!   `t,u,y,force,energy,velocity,losses,control_work,work,output` (units: s, m, m, N, J, m/s, J,
//!   J, count, as
//!   the WAV before normalisation);
//! - prints exactly one JSON line on stdout: the [`Summary`], the render's [`Measurements`] with
//!   the wall-clock time of the simulation.
//!
//! `--chunk N` renders in calls of N samples; `--chunk 0` uses sizes drawn from a seeded
//! generator (1 to 4096). Output is bit-identical for every chunking.
//!
//! A scene error names its key, exits non-zero and writes nothing. Output files are written to
//! temporary files beside their destination and renamed into place only when complete, so an
//! existing file is either left untouched or replaced by a complete new one. The scene file
//! itself is never an output.

use std::fs;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use qsa_dsp::scene::{Frame, Scene};
use qsa_dsp::scene_file::{Measurements, Run, Sampling, SceneError, SceneJob, build, fill_frames, parse_scene};
use rand::{RngExt, SeedableRng};
use tempfile::NamedTempFile;

pub mod midi;

/// Seed of the random chunk sizes of `--chunk 0`.
pub const CHUNK_SEED: u64 = 0x5eed_c4a7;

/// Arguments of `render`.
#[derive(Debug, Clone, Default, Args)]
pub struct RenderArgs {
    /// Scene file (TOML).
    #[arg(required_unless_present = "midi", conflicts_with = "midi")]
    pub scene: Option<PathBuf>,
    /// Render a MIDI file through the instrument engine instead of a scene.
    #[arg(long, value_name = "FILE.mid")]
    pub midi: Option<PathBuf>,
    /// Start --midi from a factory preset (its id or name; `cargo xtask presets` lists them);
    /// --mode and --set apply on top of it.
    #[arg(long, value_name = "NAME", requires = "midi")]
    pub preset: Option<String>,
    /// Instrument mode for --midi (same as --set mode=...).
    #[arg(long, value_parser = mode_options(), requires = "midi")]
    pub mode: Option<String>,
    /// Set a plugin parameter for --midi, by its id (the table in plugin/src/params.rs), e.g. --set hard=2
    /// --set gain=-6.
    #[arg(long = "set", value_name = "ID=VALUE", requires = "midi")]
    pub set: Vec<String>,
    /// Sample rate for --midi (Hz) [default: 48000].
    #[arg(long, requires = "midi")]
    pub rate: Option<u32>,
    /// Seconds rendered after the MIDI file's last event, its end of track included [default: 2].
    #[arg(long, requires = "midi")]
    pub tail: Option<f64>,
    /// Output WAV path [default: the input path with extension .wav].
    #[arg(long, value_name = "PATH.wav")]
    pub out: Option<PathBuf>,
    /// Also write per-sample signals to a CSV beside the WAV (scenes only).
    #[arg(long, conflicts_with = "midi")]
    pub csv: bool,
    /// Render in calls of N samples (0: seeded random sizes) [default: one call for a scene, 512
    /// samples for --midi].
    #[arg(long, value_name = "N")]
    pub chunk: Option<usize>,
    /// For --midi: write the dry signals, centred (each piano key's bridge force, each slide
    /// voice's string velocity at the pickup), without the soundboard's radiation, the stereo
    /// pan or the pickup's circuit.
    #[arg(long, requires = "midi")]
    pub raw: bool,
}

/// `--rate`'s default (Hz).
pub(crate) const MIDI_RATE: u32 = 48_000;
/// `--tail`'s default (s).
pub(crate) const MIDI_TAIL: f64 = 2.0;

/// What `--mode` takes: the option ids of the `mode` parameter.
fn mode_options() -> clap::builder::PossibleValuesParser {
    let options = match qsa_dsp::instrument::param_spec("mode").map(|spec| spec.kind) {
        Some(qsa_dsp::instrument::ParamKind::Choice { options, .. }) => options,
        _ => &[],
    };
    clap::builder::PossibleValuesParser::new(options.iter().map(|(id, _)| *id))
}

/// The summary line of a scene render: what it measured, then how long the simulation took.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Summary {
    /// What the render measured.
    #[serde(flatten)]
    pub measured: Measurements,
    /// Wall-clock time of the simulation (s).
    pub wall_seconds: f64,
    /// Real-time factor: wall seconds per simulated second.
    pub rtf: f64,
}

/// Job: every frame, in calls of the sizes an iterator gives, with the wall-clock time (s) spent
/// in [`Scene::process`].
struct TimedFrames<I> {
    chunks: I,
}

impl<I: Iterator<Item = usize>> SceneJob for TimedFrames<I> {
    type Output = (Run, f64);

    fn run(self, mut scene: impl Scene, samples: usize, segments: usize) -> (Run, f64) {
        let initial_energy = scene.initial_energy();
        let mut frames = vec![Frame::default(); samples];
        let start = Instant::now();
        fill_frames(&mut scene, &mut frames, self.chunks);
        (Run { frames, initial_energy, segments }, start.elapsed().as_secs_f64())
    }
}

/// What a render produced: the summary line it printed.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
#[serde(untagged)]
pub enum Outcome {
    /// A scene render.
    Scene(Summary),
    /// A MIDI render.
    Midi(midi::MidiSummary),
}

impl Outcome {
    /// The scene summary, if this was a scene render.
    pub fn scene(self) -> Option<Summary> {
        match self {
            Outcome::Scene(s) => Some(s),
            Outcome::Midi(_) => None,
        }
    }
}

/// Why a render failed.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The scene file could not be read.
    #[error("cannot read {path}: {source}")]
    Read {
        /// The scene file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The scene is invalid.
    #[error("{path}: {source}")]
    Scene {
        /// The scene file.
        path: PathBuf,
        /// What is wrong, naming the key.
        source: SceneError,
    },
    /// The options given do not go together (a usage error: exit code 2, as the parser's own).
    #[error("{0}")]
    Usage(String),
    /// An output path is unusable.
    #[error("{0}")]
    Output(String),
    /// The MIDI file or a parameter is invalid.
    #[error("{0}")]
    Midi(String),
    /// Writing an output failed.
    #[error("cannot write {path}: {source}")]
    Write {
        /// The destination.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
}

/// The chunk sizes `--chunk` asks for.
pub fn chunk_sizes(chunk: Option<usize>) -> Box<dyn Iterator<Item = usize>> {
    match chunk {
        None => Box::new(std::iter::empty()),
        Some(0) => {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(CHUNK_SEED);
            Box::new(std::iter::repeat_with(move || rng.random_range(1..=4096)))
        }
        Some(n) => Box::new(std::iter::repeat(n)),
    }
}

/// Run `render`, printing the summary line to `stdout`.
pub fn run(args: &RenderArgs, stdout: &mut dyn Write) -> Result<Outcome, RenderError> {
    let summary = match (&args.scene, &args.midi) {
        (_, Some(midi_path)) => Outcome::Midi(midi::run(args, midi_path)?),
        (Some(scene_path), None) => {
            // The parser cannot say so itself: an argument that conflicts with another bypasses
            // the `requires` of the others (clap issue 4520).
            let midi_only = [
                ("--preset", args.preset.is_some()),
                ("--mode", args.mode.is_some()),
                ("--set", !args.set.is_empty()),
                ("--rate", args.rate.is_some()),
                ("--tail", args.tail.is_some()),
                ("--raw", args.raw),
            ];
            if let Some((flag, _)) = midi_only.iter().find(|(_, given)| *given) {
                return Err(RenderError::Usage(format!("{flag} applies to --midi only, not to a scene file")));
            }
            Outcome::Scene(run_scene(args, scene_path)?)
        }
        (None, None) => return Err(RenderError::Usage("give a scene file or --midi FILE.mid".into())),
    };
    let line = serde_json::to_string(&summary).expect("a summary always serialises");
    writeln!(stdout, "{line}").map_err(|source| RenderError::Write { path: "<stdout>".into(), source })?;
    Ok(summary)
}

/// The most bytes a scene or MIDI file may have (16 MiB), far beyond any that is written.
pub const MAX_INPUT_BYTES: usize = 16 << 20;

/// The bytes of the input file `path`, at most [`MAX_INPUT_BYTES`]: a larger file, or a pipe or
/// device that never ends, is refused after reading one byte more, not read into memory.
pub fn read_input(path: &Path) -> Result<Vec<u8>, RenderError> {
    use std::io::Read;
    let read = |source| RenderError::Read { path: path.to_owned(), source };
    let mut bytes = Vec::new();
    fs::File::open(path).and_then(|f| f.take(MAX_INPUT_BYTES as u64 + 1).read_to_end(&mut bytes)).map_err(read)?;
    if bytes.len() > MAX_INPUT_BYTES {
        let too_long = format!("more than {MAX_INPUT_BYTES} bytes (16 MiB), the most an input may have");
        return Err(read(std::io::Error::new(std::io::ErrorKind::InvalidData, too_long)));
    }
    Ok(bytes)
}

fn run_scene(args: &RenderArgs, scene_path: &Path) -> Result<Summary, RenderError> {
    let text = String::from_utf8(read_input(scene_path)?).map_err(|e| RenderError::Read {
        path: scene_path.to_owned(),
        source: std::io::Error::new(std::io::ErrorKind::InvalidData, e.utf8_error()),
    })?;
    let scene = parse_scene(&text).map_err(|source| RenderError::Scene { path: scene_path.to_owned(), source })?;
    let wav_path = args.out.clone().unwrap_or_else(|| scene_path.with_extension("wav"));
    let csv_path = args.csv.then(|| wav_path.with_extension("csv"));
    // One file by two names: the WAV's own extension `.csv` in any case (one file on a
    // case-insensitive file system), or a link between them.
    let one_file = |csv: &PathBuf| {
        wav_path.extension().is_some_and(|e| e.eq_ignore_ascii_case("csv"))
            || matches!((fs::canonicalize(csv), fs::canonicalize(&wav_path)), (Ok(a), Ok(b)) if a == b)
    };
    if csv_path.as_ref().is_some_and(one_file) {
        return Err(RenderError::Output(format!(
            "with --csv the CSV would replace the WAV {}; give the WAV path another extension",
            wav_path.display()
        )));
    }
    for path in std::iter::once(&wav_path).chain(csv_path.as_ref()) {
        check_output_path(path, scene_path)?;
    }
    let common = scene.common();
    let (rendered, wall_seconds) =
        build(&scene, &common.solver, Sampling::NATIVE, TimedFrames { chunks: chunk_sizes(args.chunk) })
            .map_err(|source| RenderError::Scene { path: scene_path.to_owned(), source })?;
    let options = common.output;
    let scale = wav_scale(&rendered, options.normalize, options.gain);
    if let Some(n) = rendered.frames.iter().position(|f| !((f.output * scale) as f32).is_finite()) {
        let why = if f64::is_finite(rendered.frames[n].output) {
            format!("with [output] gain = {} the output exceeds 32-bit float", options.gain)
        } else {
            "the simulation left the numbers a float holds: a parameter is beyond what the scheme can simulate"
                .to_owned()
        };
        return Err(RenderError::Output(format!(
            "{}: not finite from sample {n} on ({why}); nothing was written",
            scene_path.display()
        )));
    }
    let measured = Measurements::measure(&scene, &rendered);
    let duration = rendered.frames.len() as f64 * (1.0 / common.sample_rate as f64);
    let summary = Summary { measured, wall_seconds, rtf: wall_seconds / duration };
    let wav = write_temp(&wav_path, |w| write_wav(w, &rendered, common.sample_rate, scale))?;
    let csv = match &csv_path {
        Some(path) => Some((write_temp(path, |w| write_csv(w, &rendered, common.sample_rate))?, path)),
        None => None,
    };
    wav.persist()?;
    if let Some((file, _)) = csv {
        file.persist()?;
    }
    Ok(summary)
}

pub(crate) fn check_output_path(path: &Path, scene: &Path) -> Result<(), RenderError> {
    let same = match (fs::canonicalize(path), fs::canonicalize(scene)) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if same {
        return Err(RenderError::Output(format!(
            "refusing to overwrite the input file {} with output",
            scene.display()
        )));
    }
    let dir = parent_dir(path);
    if !dir.is_dir() {
        return Err(RenderError::Output(format!("output directory {} does not exist", dir.display())));
    }
    if path.is_dir() {
        return Err(RenderError::Output(format!("output path {} is a directory", path.display())));
    }
    Ok(())
}

fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}

/// An output written, waiting to take its place ([`Staged::persist`]).
#[must_use = "an output takes its place only when persisted"]
pub(crate) struct Staged {
    /// The temporary file and the path it becomes; none when the output went straight into a
    /// file that is not a regular one.
    temp: Option<(NamedTempFile, PathBuf)>,
}

impl Staged {
    /// Put the output in its place (a rename, so a failed render never leaves half a file).
    pub(crate) fn persist(self) -> Result<(), RenderError> {
        if let Some((file, path)) = self.temp {
            file.persist(&path).map_err(|e| RenderError::Write { path, source: e.error })?;
        }
        Ok(())
    }
}

/// Write an output for `path`: into a temporary file beside the file `path` names (through any
/// symbolic links, which stay), renamed into place by [`Staged::persist`]; or, when `path` names
/// something other than a regular file (`/dev/null`, a pipe, a terminal), straight into it,
/// which is then never replaced.
pub(crate) fn write_temp(
    path: &Path,
    write: impl FnOnce(&mut BufWriter<&std::fs::File>) -> std::io::Result<()>,
) -> Result<Staged, RenderError> {
    let err = |source| RenderError::Write { path: path.to_owned(), source };
    let target = fs::canonicalize(path).unwrap_or_else(|_| path.to_owned());
    if fs::metadata(&target).is_ok_and(|m| !m.is_file()) {
        let file = fs::OpenOptions::new().write(true).open(&target).map_err(err)?;
        let mut w = BufWriter::new(&file);
        write(&mut w).map_err(err)?;
        w.flush().map_err(err)?;
        return Ok(Staged { temp: None });
    }
    let mut builder = tempfile::Builder::new();
    // Outputs are ordinary files (the temporary default is owner-only).
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o644));
    let file = builder.tempfile_in(parent_dir(&target)).map_err(err)?;
    let mut w = BufWriter::new(file.as_file());
    write(&mut w).map_err(err)?;
    w.flush().map_err(err)?;
    drop(w);
    file.as_file().sync_all().map_err(err)?;
    Ok(Staged { temp: Some((file, target)) })
}

/// The factor the WAV's samples are the output times: `gain`, over the peak when normalising.
fn wav_scale(rendered: &Run, normalize: bool, gain: f64) -> f64 {
    let peak = rendered.frames.iter().fold(0.0_f64, |m, f| m.max(f.output.abs()));
    if normalize && peak > 0.0 { gain / peak } else { gain }
}

fn write_wav(w: &mut impl Write, rendered: &Run, sample_rate: u32, scale: f64) -> std::io::Result<()> {
    let spec =
        hound::WavSpec { channels: 1, sample_rate, bits_per_sample: 32, sample_format: hound::SampleFormat::Float };
    // hound needs Seek to patch the header; write into memory and copy out.
    let mut buffer = std::io::Cursor::new(Vec::with_capacity(44 + 4 * rendered.frames.len()));
    {
        let mut wav = hound::WavWriter::new(&mut buffer, spec).map_err(std::io::Error::other)?;
        for f in &rendered.frames {
            wav.write_sample((f.output * scale) as f32).map_err(std::io::Error::other)?;
        }
        wav.finalize().map_err(std::io::Error::other)?;
    }
    w.write_all(buffer.get_ref())
}

fn write_csv(w: &mut impl Write, rendered: &Run, sample_rate: u32) -> std::io::Result<()> {
    let dt = 1.0 / sample_rate as f64;
    writeln!(w, "t,u,y,force,energy,velocity,losses,control_work,work,output")?;
    for (n, f) in rendered.frames.iter().enumerate() {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{},{},{}",
            n as f64 * dt,
            f.displacement,
            f.compression,
            f.force,
            f.energy,
            f.velocity,
            f.losses,
            f.control_work,
            f.work,
            f.output
        )?;
    }
    Ok(())
}
