//! Contract tests of `cargo xtask render <scene.toml> [--out PATH.wav] [--csv] [--chunk N]`,
//! run in-process through `xtask::run` (exit code, stdout, stderr) and `xtask::render::run`.
//!
//! The contract:
//! - a 32-bit float mono WAV, peak-normalised unless `[output] normalize = false`, then scaled by
//!   `[output] gain`; with `--csv` a CSV beside it whose header starts `t,u,y,force,energy`;
//! - the same bytes for every `--chunk` (1, 64, 1000, 0 = seeded random sizes, or none);
//! - exactly one JSON summary line on stdout, with physically right values for the seed's Fig. 4
//!   (docs/physics.md §9.1: y_max = 8.7162e-5 m, F_max = 527.75 N, rebound at −v0);
//! - a scene error names its key and reason, exits non-zero and leaves no output behind; an
//!   existing output is only ever replaced by a complete new one; the scene file is never an
//!   output.
//!
//! Every output goes into a temporary directory; nothing is written into the repository.

use std::collections::BTreeSet;
use std::ffi::OsString;
use std::fs;
use std::path::{Path, PathBuf};

use qsa_dsp::scene_file::{parse_scene, render};
use rand::{RngExt, SeedableRng};
use serde_json::Value;
use tempfile::TempDir;
use xtask::render::{RenderArgs, Summary, chunk_sizes};

// ------------------------------------------------------------------------------------------------
// Fixtures and helpers
// ------------------------------------------------------------------------------------------------

/// Analytic peak compression of the Fig. 4 contact (docs/physics.md §9.1), m.
const FIG4_Y_MAX: f64 = 8.7162e-5;
/// Analytic peak contact force of the Fig. 4 contact (docs/physics.md §9.1), N.
const FIG4_F_MAX: f64 = 527.75;
/// Fig. 4 initial velocity (m/s); the mass must leave at exactly −V0.
const FIG4_V0: f64 = 2.0;

/// A complete, valid scene that mirrors `scenes/fig4-mass-barrier.toml` with every optional
/// table written out, so that malformed variants can be made by editing one line.
const BASE: &str = r#"version = 1
scene = "mass-barrier"
sample_rate = 44100
duration = 0.002

[solver]
method = "qsa"
segments = 5

[contact]
kappa = 1e8
alpha = 1.3

[mass]
mass = 0.01
u0 = -1e-3
v0 = 2.0

[barrier]
position = 0.0

[output]
normalize = true
gain = 1.0
"#;

/// The repository's Fig. 4 scene file (read only; always copied before rendering).
fn fig4_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fig4-mass-barrier.toml")
}

fn fig4_text() -> String {
    fs::read_to_string(fig4_path()).expect("scenes/fig4-mass-barrier.toml is readable")
}

/// Replace exactly one occurrence of `from` in `text`; panics if `from` is absent or repeated,
/// so a typo in a test cannot silently leave the scene valid.
fn edit(text: &str, from: &str, to: &str) -> String {
    assert_eq!(text.matches(from).count(), 1, "`{from}` must occur exactly once in the scene");
    text.replacen(from, to, 1)
}

/// The Fig. 4 scene with another solver.
fn fig4_with_method(method: &str) -> String {
    let text = fig4_text();
    let line = text.lines().find(|l| l.starts_with("method")).expect("the Fig. 4 scene names a method").to_owned();
    edit(&text, &line, &format!("method = \"{method}\""))
}

/// What one `xtask::run` call produced.
#[derive(Debug)]
struct Outcome {
    code: i32,
    stdout: String,
    stderr: String,
}

fn xtask<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> Outcome {
    let args: Vec<OsString> = args.iter().map(|a| a.as_ref().to_owned()).collect();
    let mut stdout = Vec::new();
    let mut stderr = Vec::new();
    let code = xtask::run(args, &mut stdout, &mut stderr);
    Outcome {
        code,
        stdout: String::from_utf8(stdout).expect("stdout is UTF-8"),
        stderr: String::from_utf8(stderr).expect("stderr is UTF-8"),
    }
}

/// `render <scene> [extra…]`.
fn render_cmd(scene: &Path, extra: &[&str]) -> Outcome {
    let mut args: Vec<OsString> = vec!["render".into(), scene.into()];
    args.extend(extra.iter().map(OsString::from));
    xtask(&args)
}

/// `render <scene> --out <out> [extra…]`.
fn render_to(scene: &Path, out: &Path, extra: &[&str]) -> Outcome {
    let mut args: Vec<OsString> = vec!["render".into(), scene.into(), "--out".into(), out.into()];
    args.extend(extra.iter().map(OsString::from));
    xtask(&args)
}

fn write_scene(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    fs::write(&path, text).unwrap();
    path
}

/// Names of the entries of `dir`.
fn listing(dir: &Path) -> BTreeSet<String> {
    fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect()
}

fn names(list: &[&str]) -> BTreeSet<String> {
    list.iter().map(|s| (*s).to_owned()).collect()
}

/// The single JSON line on stdout of a successful render.
fn summary_line(out: &Outcome) -> Value {
    assert_eq!(out.code, 0, "render failed: {}", out.stderr);
    assert!(out.stdout.ends_with('\n'), "the summary line ends with a newline: {:?}", out.stdout);
    assert_eq!(out.stdout.lines().count(), 1, "exactly one line on stdout: {:?}", out.stdout);
    let json: Value = serde_json::from_str(out.stdout.trim_end()).expect("the summary line is JSON");
    assert!(json.is_object(), "the summary is a JSON object: {json}");
    json
}

fn num(json: &Value, key: &str) -> f64 {
    json[key].as_f64().unwrap_or_else(|| panic!("summary field `{key}` is a number: {json}"))
}

fn int(json: &Value, key: &str) -> u64 {
    json[key].as_u64().unwrap_or_else(|| panic!("summary field `{key}` is a whole number: {json}"))
}

/// The summary without its timing fields (which differ run to run).
fn without_timing(json: &Value) -> Value {
    let mut json = json.clone();
    let map = json.as_object_mut().unwrap();
    assert!(map.remove("wall_seconds").is_some());
    assert!(map.remove("rtf").is_some());
    json
}

/// A CSV: its header and its rows, every cell parsed as f64.
struct Csv {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Csv {
    fn read(path: &Path) -> Self {
        let text = fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header: Vec<String> = lines.next().expect("a header line").split(',').map(str::to_owned).collect();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                l.split(',').map(|c| c.parse::<f64>().unwrap_or_else(|_| panic!("cell {c:?} is a number"))).collect()
            })
            .collect();
        for row in &rows {
            assert_eq!(row.len(), header.len(), "every row has a cell per column");
        }
        Self { header, rows }
    }

    fn column(&self, name: &str) -> Vec<f64> {
        let i = self.header.iter().position(|h| h == name).unwrap_or_else(|| panic!("CSV column {name}"));
        self.rows.iter().map(|r| r[i]).collect()
    }
}

/// Largest magnitude.
fn peak_abs(values: &[f64]) -> f64 {
    values.iter().fold(0.0_f64, |m, v| m.max(v.abs()))
}

/// Equal to a few ulps (JSON numbers parsed by serde_json without `float_roundtrip`).
fn assert_close(a: f64, b: f64, what: &str) {
    assert!((a - b).abs() <= 4.0 * f64::EPSILON * b.abs(), "{what}: {a} vs {b}");
}

fn read_wav(path: &Path) -> (hound::WavSpec, Vec<f32>) {
    let mut reader = hound::WavReader::open(path).expect("a readable WAV");
    let spec = reader.spec();
    let samples = reader.samples::<f32>().map(|s| s.unwrap()).collect();
    (spec, samples)
}

// ------------------------------------------------------------------------------------------------
// The summary line and the physics of Fig. 4
// ------------------------------------------------------------------------------------------------

const SUMMARY_FIELDS: &[&str] = &[
    "scene",
    "method",
    "segments",
    "sample_rate",
    "samples",
    "contact_samples",
    "contacts",
    "peak_force",
    "max_compression",
    "rebound_velocity",
    "energy_drift_rel",
    "wall_seconds",
    "rtf",
];

/// Render the Fig. 4 scene with `method` and check the summary against the analytic contact.
fn check_fig4_summary(method: &str, segments: u64) {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "fig4.toml", &fig4_with_method(method));
    let wav = dir.path().join("out.wav");
    let out = render_to(&scene, &wav, &["--csv"]);
    let json = summary_line(&out);
    assert_eq!(out.stderr, "", "a good render writes nothing to stderr");
    for field in SUMMARY_FIELDS {
        assert!(json.get(field).is_some(), "summary has `{field}`: {json}");
    }

    assert_eq!(json["scene"], "mass-barrier");
    assert_eq!(json["method"], method);
    assert_eq!(int(&json, "segments"), segments);
    assert_eq!(int(&json, "sample_rate"), 44100);
    let duration = 0.002;
    assert_eq!(int(&json, "samples"), (duration * 44100.0_f64).round() as u64);
    assert_eq!(int(&json, "samples"), 88);

    // One contact, elastic: the mass leaves at −V0, energy conserved to rounding.
    assert_eq!(int(&json, "contacts"), 1, "{json}");
    let rebound = num(&json, "rebound_velocity");
    assert!((rebound + FIG4_V0).abs() <= 1e-9, "{method}: rebound velocity {rebound} m/s, want −2");
    let drift = num(&json, "energy_drift_rel");
    assert!((0.0..=1e-12).contains(&drift), "{method}: energy drift {drift}");

    // The contact lasts T_c = 1.313e-4 s ≈ 5.8 samples; with the samples at each end where the
    // discrete-gradient force is already/still non-zero, about 8 samples carry a force.
    let contact_samples = int(&json, "contact_samples");
    let (lo, hi) = if method == "exp" { (5, 9) } else { (7, 9) };
    assert!((lo..=hi).contains(&contact_samples), "{method}: {contact_samples} contact samples");

    // The summary's extremes are those of the per-sample signals.
    let csv = Csv::read(&dir.path().join("out.csv"));
    let force = csv.column("force");
    let y = csv.column("y");
    assert_eq!(force.iter().filter(|f| **f != 0.0).count() as u64, contact_samples);
    // (serde_json's default float parsing may be off by an ulp; the CSV parses exactly.)
    assert_close(num(&json, "peak_force"), peak_abs(&force), "peak_force");
    assert_close(num(&json, "max_compression"), y.iter().fold(f64::NEG_INFINITY, |m, v| m.max(*v)), "max_compression");

    // Physics: sampled extremes close to the analytic ones (sampling only lowers the force peak;
    // the discrete contact's peak compression is within 5 % for the implicit schemes).
    let y_max = num(&json, "max_compression");
    if method != "exp" {
        let rel = (y_max - FIG4_Y_MAX).abs() / FIG4_Y_MAX;
        assert!(rel <= 0.05, "{method}: max compression {y_max} m is {:.1} % from {FIG4_Y_MAX}", 100.0 * rel);
    } else {
        // EXP on this coarse grid overshoots more (measured ≈ 18 %); it must still be a
        // compression of the right order.
        assert!(y_max > FIG4_Y_MAX && y_max < 1.25 * FIG4_Y_MAX, "exp: max compression {y_max} m");
    }
    let peak = num(&json, "peak_force");
    assert!(peak > 0.8 * FIG4_F_MAX && peak <= 1.05 * FIG4_F_MAX, "{method}: peak force {peak} N");

    // Timing fields are consistent.
    let wall = num(&json, "wall_seconds");
    let rtf = num(&json, "rtf");
    assert!(wall.is_finite() && wall >= 0.0);
    let simulated = 88.0 / 44100.0;
    assert!((rtf - wall / simulated).abs() <= 1e-12 * rtf.max(1e-300), "rtf {rtf} vs wall {wall}");
}

#[test]
fn fig4_summary_is_one_json_line_with_the_analytic_physics_qsa() {
    check_fig4_summary("qsa", 5);
}

#[test]
fn fig4_summary_is_one_json_line_with_the_analytic_physics_imp() {
    check_fig4_summary("imp", 0);
}

#[test]
fn fig4_summary_is_one_json_line_with_the_analytic_physics_exp() {
    check_fig4_summary("exp", 0);
}

#[test]
fn fig4_scene_file_renders_as_is_next_to_a_copy() {
    // The repository's scene file, unchanged, rendered to the default output path (beside a copy).
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("fig4-mass-barrier.toml");
    fs::copy(fig4_path(), &scene).unwrap();
    let out = render_cmd(&scene, &[]);
    let json = summary_line(&out);
    assert_eq!(json["method"], "qsa");
    assert_eq!(int(&json, "segments"), 5);
    assert_eq!(int(&json, "contacts"), 1);
    assert_eq!(listing(dir.path()), names(&["fig4-mass-barrier.toml", "fig4-mass-barrier.wav"]));
    assert_eq!(fs::read(&scene).unwrap(), fs::read(fig4_path()).unwrap(), "the scene file is untouched");
}

#[test]
fn in_process_run_returns_the_summary_it_prints() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "s.toml", BASE);
    let args = RenderArgs {
        scene: Some(scene.clone()),
        out: Some(dir.path().join("o.wav")),
        chunk: Some(7),
        ..RenderArgs::default()
    };
    let mut stdout = Vec::new();
    let summary: Summary =
        xtask::render::run(&args, &mut stdout).expect("the base scene renders").scene().expect("a scene summary");
    let text = String::from_utf8(stdout).unwrap();
    assert_eq!(text.lines().count(), 1);
    let json: Value = serde_json::from_str(text.trim_end()).unwrap();
    let want = serde_json::to_value(&summary).unwrap();
    let (got, want) = (json.as_object().unwrap(), want.as_object().unwrap());
    assert_eq!(got.keys().collect::<Vec<_>>(), want.keys().collect::<Vec<_>>());
    for (key, w) in want {
        match (got[key].as_f64(), w.as_f64()) {
            (Some(g), Some(w)) => assert_close(g, w, key),
            _ => assert_eq!(&got[key], w, "{key}"),
        }
    }
    assert_eq!(summary.measured.contacts, 1);
    assert_eq!(summary.measured.samples, 88);
    assert_eq!(listing(dir.path()), names(&["s.toml", "o.wav"]));
}

// ------------------------------------------------------------------------------------------------
// WAV and CSV contents
// ------------------------------------------------------------------------------------------------

/// Render `text` to `out.wav` + `out.csv` in a fresh directory.
fn render_files(text: &str) -> (TempDir, Value, (hound::WavSpec, Vec<f32>), Csv) {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "s.toml", text);
    let wav = dir.path().join("out.wav");
    let json = summary_line(&render_to(&scene, &wav, &["--csv"]));
    let wav_data = read_wav(&wav);
    let csv = Csv::read(&dir.path().join("out.csv"));
    (dir, json, wav_data, csv)
}

#[test]
fn wav_is_mono_float32_and_peak_normalised() {
    let (_dir, json, (spec, samples), csv) = render_files(BASE);
    assert_eq!(spec.channels, 1);
    assert_eq!(spec.sample_rate, 44100);
    assert_eq!(spec.bits_per_sample, 32);
    assert_eq!(spec.sample_format, hound::SampleFormat::Float);
    assert_eq!(samples.len() as u64, int(&json, "samples"));

    // Peak-normalised: the loudest sample is ±1, and every sample is the output over the peak.
    let peak_out = samples.iter().fold(0.0_f32, |m, s| m.max(s.abs()));
    assert!((peak_out - 1.0).abs() <= 1e-6, "normalised peak {peak_out}");
    let output = csv.column("output");
    assert_close(num(&json, "peak_force"), peak_abs(&output), "peak_force vs the output column");
    let scale = 1.0 / peak_abs(&output);
    for (n, (w, o)) in samples.iter().zip(&output).enumerate() {
        assert_eq!(w.to_bits(), ((o * scale) as f32).to_bits(), "sample {n}: {w} vs {o} × {scale}");
    }
    assert!(samples.iter().any(|s| *s != 0.0));
}

#[test]
fn wav_gain_applies_after_normalisation() {
    let text = edit(BASE, "gain = 1.0", "gain = 0.5");
    let (_dir, _json, (_, samples), csv) = render_files(&text);
    let peak_out = samples.iter().fold(0.0_f32, |m, s| m.max(s.abs()));
    assert!((peak_out - 0.5).abs() <= 1e-6, "peak {peak_out} with gain 0.5");
    let output = csv.column("output");
    let scale = 0.5 / peak_abs(&output);
    for (w, o) in samples.iter().zip(output) {
        assert_eq!(w.to_bits(), ((o * scale) as f32).to_bits());
    }
}

#[test]
fn wav_is_not_normalised_when_the_scene_says_so() {
    let text = edit(&edit(BASE, "normalize = true", "normalize = false"), "gain = 1.0", "gain = 1e-3");
    let (_dir, json, (_, samples), csv) = render_files(&text);
    // Raw force (N) times the gain: the peak is F_peak × 1e-3, not 1.
    let peak_out = samples.iter().fold(0.0_f32, |m, s| m.max(s.abs()));
    assert_eq!(peak_out, (peak_abs(&csv.column("output")) * 1e-3) as f32);
    assert_close(num(&json, "peak_force"), peak_abs(&csv.column("force")), "peak_force");
    assert!(peak_out > 0.4 && peak_out < 0.53, "raw peak {peak_out}");
    for (w, o) in samples.iter().zip(csv.column("output")) {
        assert_eq!(w.to_bits(), ((o * 1e-3) as f32).to_bits());
    }
}

#[test]
fn csv_header_rows_and_columns() {
    let (_dir, json, _, csv) = render_files(BASE);
    assert_eq!(&csv.header[..5], &["t", "u", "y", "force", "energy"], "header {:?}", csv.header);
    assert_eq!(csv.rows.len() as u64, int(&json, "samples"));
    let dt = 1.0 / 44100.0;
    for (n, t) in csv.column("t").iter().enumerate() {
        assert_eq!(*t, n as f64 * dt, "t of row {n}");
    }
    // Barrier at 0: displacement equals compression; the mass starts at u0 = −1 mm.
    let (u, y) = (csv.column("u"), csv.column("y"));
    assert_eq!(u, y);
    assert_eq!(u[0], -1e-3);
    // Forces are never adhesive, and the energy stays at ½ m v0² = 0.02 J to rounding.
    assert!(csv.column("force").iter().all(|f| *f <= 0.0));
    for e in csv.column("energy") {
        assert!((e - 0.02).abs() <= 1e-12 * 0.02, "energy {e}");
    }
}

// ------------------------------------------------------------------------------------------------
// Chunking: byte-identical outputs
// ------------------------------------------------------------------------------------------------

const CHUNK_FLAGS: &[Option<&str>] = &[None, Some("1"), Some("64"), Some("1000"), Some("0")];

/// Render `text` once per chunk flag and check WAV and CSV bytes and the summary all agree.
/// Returns the CSV of the unchunked render.
fn check_chunking(text: &str, label: &str) -> Csv {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "s.toml", text);
    let mut reference: Option<(Vec<u8>, Vec<u8>, Value)> = None;
    for (i, flag) in CHUNK_FLAGS.iter().enumerate() {
        let wav = dir.path().join(format!("out{i}.wav"));
        let extra: Vec<&str> = match flag {
            Some(n) => vec!["--csv", "--chunk", n],
            None => vec!["--csv"],
        };
        let json = without_timing(&summary_line(&render_to(&scene, &wav, &extra)));
        let wav_bytes = fs::read(&wav).unwrap();
        let csv_bytes = fs::read(wav.with_extension("csv")).unwrap();
        match &reference {
            None => reference = Some((wav_bytes, csv_bytes, json)),
            Some((w, c, j)) => {
                assert!(wav_bytes == *w, "{label}: WAV with --chunk {flag:?} differs from one call");
                assert!(csv_bytes == *c, "{label}: CSV with --chunk {flag:?} differs from one call");
                assert_eq!(json, *j, "{label}: summary with --chunk {flag:?} differs");
            }
        }
    }
    Csv::read(&dir.path().join("out0.csv"))
}

#[test]
fn fig4_output_is_byte_identical_for_every_chunking_and_method() {
    for method in ["qsa", "imp", "exp"] {
        let csv = check_chunking(&fig4_with_method(method), &format!("fig4 {method}"));
        // --chunk 64 splits this render inside its contact only if the contact is near sample 64;
        // --chunk 1 always splits it; the render must have had a contact at all.
        assert!(csv.column("force").iter().any(|f| *f != 0.0), "{method}: no contact");
    }
}

#[test]
fn late_contact_split_by_every_chunking_is_byte_identical() {
    // 0.2 s (8820 samples) with the contact starting just before sample 1000, so `--chunk 1000`
    // splits the contact itself and the seeded random sizes split the render several times.
    let samples = 8820;
    let mut boundaries = Vec::new();
    let mut at = 0;
    for n in chunk_sizes(Some(0)) {
        at += n;
        if at >= samples {
            break;
        }
        boundaries.push(at);
    }
    assert!(boundaries.len() >= 2, "--chunk 0 must split an {samples}-sample render: {boundaries:?}");

    for method in ["qsa", "imp", "exp"] {
        let text =
            edit(&edit(&fig4_with_method(method), "duration = 0.002", "duration = 0.2"), "u0 = -1e-3", "u0 = -0.04525");
        let csv = check_chunking(&text, &format!("late {method}"));
        let force = csv.column("force");
        assert_eq!(force.len(), samples);
        assert!(force[999] != 0.0 && force[1000] != 0.0, "{method}: the contact straddles sample 1000");
        assert!(force.iter().filter(|f| **f != 0.0).count() >= 5, "{method}: a contact of several samples");
    }
}

#[test]
fn engine_frames_are_identical_for_random_small_chunks() {
    // Directly through the engine: chunk sizes 1 to 5 drawn from a seeded generator, so chunk
    // boundaries fall at many places inside the contact.
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0x0c4a_11ed);
    for method in ["qsa", "imp", "exp"] {
        let scene = parse_scene(&fig4_with_method(method)).unwrap();
        let whole = render(&scene, std::iter::empty()).unwrap();
        for _ in 0..20 {
            let sizes: Vec<usize> = (0..200).map(|_| rng.random_range(1..=5)).collect();
            let split = render(&scene, sizes.into_iter()).unwrap();
            assert_eq!(split.frames, whole.frames, "{method}: frames differ for random chunks");
        }
    }
}

// ------------------------------------------------------------------------------------------------
// Malformed scenes
// ------------------------------------------------------------------------------------------------

/// A malformed scene and what its error must mention (the key, and a word of the reason).
struct Bad {
    what: &'static str,
    text: String,
    needles: &'static [&'static str],
}

fn bad(what: &'static str, text: String, needles: &'static [&'static str]) -> Bad {
    Bad { what, text, needles }
}

fn bad_scenes() -> Vec<Bad> {
    let e = |from: &str, to: &str| edit(BASE, from, to);
    let drop = |line: &str| edit(BASE, line, "");
    vec![
        // Misspelt keys, one per level.
        bad(
            "misspelt top-level key",
            e("sample_rate = 44100", "sample_rat = 44100"),
            &["`sample_rat`", "unknown field"],
        ),
        bad("misspelt duration", e("duration = 0.002", "durration = 0.002"), &["`durration`", "unknown field"]),
        bad("misspelt solver key", e("method = \"qsa\"", "methd = \"qsa\""), &["`methd`", "unknown field"]),
        bad("misspelt segments", e("segments = 5", "segment = 5"), &["`segment`", "unknown field"]),
        bad("misspelt v_ref", e("segments = 5", "segments = 5\nvref = 0.02"), &["`vref`", "unknown field"]),
        bad("misspelt contact key", e("kappa = 1e8", "kapa = 1e8"), &["`kapa`", "unknown field"]),
        bad("misspelt alpha", e("alpha = 1.3", "alfa = 1.3"), &["`alfa`", "unknown field"]),
        bad("misspelt mass key", e("mass = 0.01", "mas = 0.01"), &["`mas`", "unknown field"]),
        bad("misspelt u0", e("u0 = -1e-3", "u_0 = -1e-3"), &["`u_0`", "unknown field"]),
        bad("misspelt barrier key", e("position = 0.0", "positon = 0.0"), &["`positon`", "unknown field"]),
        bad("misspelt output key", e("normalize = true", "normalise = true"), &["`normalise`", "unknown field"]),
        bad("misspelt gain", e("gain = 1.0", "gian = 1.0"), &["`gian`", "unknown field"]),
        bad("key in the wrong table", e("v0 = 2.0", "v0 = 2.0\nposition = 0.0"), &["`position`", "unknown field"]),
        // Unknown tables.
        bad("unknown table", format!("{BASE}\n[extra]\nx = 1\n"), &["`extra`", "unknown field"]),
        bad("misspelt table", e("[contact]", "[contacts]"), &["`contacts`", "unknown field"]),
        bad("unknown sub-table", format!("{BASE}\n[mass.spring]\nk = 1.0\n"), &["`spring`", "unknown field"]),
        // Values out of their domain.
        bad("negative mass", e("mass = 0.01", "mass = -0.01"), &["mass.mass", "> 0"]),
        bad("zero mass", e("mass = 0.01", "mass = 0.0"), &["mass.mass", "> 0"]),
        bad("zero kappa", e("kappa = 1e8", "kappa = 0.0"), &["contact.kappa", "> 0"]),
        bad("negative kappa", e("kappa = 1e8", "kappa = -1e8"), &["contact.kappa", "> 0"]),
        bad("alpha below 1", e("alpha = 1.3", "alpha = 0.9"), &["contact.alpha", ">= 1"]),
        bad("zero segments", e("segments = 5", "segments = 0"), &["solver.segments", "must be"]),
        bad("negative segments", e("segments = 5", "segments = -3"), &["solver.segments", "must be"]),
        bad("negative v_ref", e("segments = 5", "segments = 5\nv_ref = -0.02"), &["solver.v_ref", "> 0"]),
        bad(
            "non-integer sample rate",
            e("sample_rate = 44100", "sample_rate = 44100.5"),
            &["sample_rate", "whole number"],
        ),
        bad("zero sample rate", e("sample_rate = 44100", "sample_rate = 0"), &["sample_rate", "> 0"]),
        bad("negative sample rate", e("sample_rate = 44100", "sample_rate = -44100"), &["sample_rate", "> 0"]),
        bad("zero duration", e("duration = 0.002", "duration = 0.0"), &["duration", "> 0"]),
        bad("negative duration", e("duration = 0.002", "duration = -0.002"), &["duration", "> 0"]),
        bad("duration under one sample", e("duration = 0.002", "duration = 1e-9"), &["duration", "samples"]),
        bad("overlong duration", e("duration = 0.002", "duration = 1e6"), &["duration", "at most"]),
        bad(
            "more frames than memory should hold",
            e("duration = 0.002", "duration = 600.0\nsample_rate = 96000").replace("sample_rate = 44100\n", ""),
            &["duration", "57600000 samples", "must be 1 to 14000000"],
        ),
        // NaN and infinity, written as TOML `nan` / `inf`.
        bad("nan kappa", e("kappa = 1e8", "kappa = nan"), &["contact.kappa", "finite"]),
        bad("inf kappa", e("kappa = 1e8", "kappa = inf"), &["contact.kappa", "finite"]),
        bad("nan alpha", e("alpha = 1.3", "alpha = nan"), &["contact.alpha", "finite"]),
        bad("nan mass", e("mass = 0.01", "mass = nan"), &["mass.mass", "finite"]),
        bad("inf mass", e("mass = 0.01", "mass = +inf"), &["mass.mass", "finite"]),
        bad("nan u0", e("u0 = -1e-3", "u0 = nan"), &["mass.u0", "finite"]),
        bad("inf v0", e("v0 = 2.0", "v0 = -inf"), &["mass.v0", "finite"]),
        bad("nan barrier", e("position = 0.0", "position = nan"), &["barrier.position", "finite"]),
        bad("nan sample rate", e("sample_rate = 44100", "sample_rate = nan"), &["sample_rate", "finite"]),
        bad("inf sample rate", e("sample_rate = 44100", "sample_rate = inf"), &["sample_rate", "finite"]),
        bad("inf duration", e("duration = 0.002", "duration = inf"), &["duration", "finite"]),
        bad("nan v_ref", e("segments = 5", "segments = 5\nv_ref = nan"), &["solver.v_ref", "finite"]),
        // A speed whose energy ½ m v0² leaves the floats: the default V_ref is named as a default.
        bad("v0 beyond the floats", e("v0 = 2.0", "v0 = 1e160"), &["solver.v_ref", "not given", "speeds"]),
        bad("inf gain", e("gain = 1.0", "gain = inf"), &["output.gain", "finite"]),
        // A mass whose coupling Δt²/m leaves the floats (the explicit solver then returns NaN).
        bad("mass too light for the floats", e("mass = 0.01", "mass = 1e-320"), &["mass.mass", "at least 1e-9 kg"]),
        // A default V_ref in the floats whose compression under the law is not.
        bad(
            "default v_ref compressing beyond the floats",
            e("kappa = 1e8", "kappa = 1e-300")
                .replace("alpha = 1.3", "alpha = 1")
                .replace("mass = 0.01", "mass = 1000.0")
                .replace("v0 = 2.0", "v0 = 1000.0"),
            &["solver.v_ref", "not given", "compresses this contact law"],
        ),
        // Wrong types.
        bad(
            "string sample rate",
            e("sample_rate = 44100", "sample_rate = \"44100\""),
            &["sample_rate", "invalid type"],
        ),
        bad("boolean duration", e("duration = 0.002", "duration = true"), &["duration", "invalid type"]),
        bad("integer method", e("method = \"qsa\"", "method = 1"), &["method = 1", "wanted string"]),
        bad("float segments", e("segments = 5", "segments = 5.5"), &["segments", "invalid type"]),
        bad("nan segments", e("segments = 5", "segments = nan"), &["segments", "invalid type"]),
        bad("string kappa", e("kappa = 1e8", "kappa = \"1e8\""), &["kappa", "invalid type"]),
        bad("string mass", e("mass = 0.01", "mass = \"heavy\""), &["mass", "invalid type"]),
        bad("string normalize", e("normalize = true", "normalize = \"yes\""), &["normalize", "invalid type"]),
        bad("array position", e("position = 0.0", "position = [0.0]"), &["position", "invalid type"]),
        bad(
            "solver not a table",
            e("[solver]\nmethod = \"qsa\"\nsegments = 5\n", "solver = \"qsa\"\n"),
            &["solver", "invalid type"],
        ),
        bad("scene not a string", e("scene = \"mass-barrier\"", "scene = 3"), &["scene", "string"]),
        // Unknown names.
        bad("unknown method", e("method = \"qsa\"", "method = \"newton\""), &["method", "`newton`"]),
        bad("capitalised method", e("method = \"qsa\"", "method = \"QSA\""), &["method", "`QSA`"]),
        bad(
            "unknown scene kind",
            e("scene = \"mass-barrier\"", "scene = \"trampoline\""),
            &["scene", "unknown scene kind \"trampoline\""],
        ),
        // Versions.
        bad("version 2", e("version = 1", "version = 2"), &["version", "got 2"]),
        bad("version 0", e("version = 1", "version = 0"), &["version", "got 0"]),
        bad("string version", e("version = 1", "version = \"1\""), &["version", "\"1\""]),
        bad("float version", e("version = 1", "version = 1.0"), &["version", "1.0"]),
        // Missing required keys.
        bad("missing scene", drop("scene = \"mass-barrier\"\n"), &["scene", "missing"]),
        bad("missing sample rate", drop("sample_rate = 44100\n"), &["sample_rate", "missing"]),
        bad("missing duration", drop("duration = 0.002\n"), &["duration", "missing"]),
        bad("missing method", drop("method = \"qsa\"\n"), &["method", "missing"]),
        bad("missing kappa", drop("kappa = 1e8\n"), &["kappa", "missing"]),
        bad("missing mass", drop("mass = 0.01\n"), &["mass", "missing"]),
        bad("missing barrier table", drop("[barrier]\nposition = 0.0\n"), &["barrier", "missing"]),
        // Duplicate key, not TOML, empty.
        bad("duplicate key", e("mass = 0.01", "mass = 0.01\nmass = 0.02"), &["mass", "duplicate"]),
        bad("not TOML", "this is not a scene file {\n".to_owned(), &["TOML parse error", "line 1"]),
        bad("JSON, not TOML", "{\"scene\": \"mass-barrier\"}\n".to_owned(), &["TOML parse error", "line 1"]),
        bad("empty file", String::new(), &["scene", "missing"]),
    ]
}

#[test]
fn the_base_scene_is_valid() {
    // The control for every malformed variant below.
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let json = summary_line(&render_cmd(&scene, &["--csv"]));
    assert_eq!(int(&json, "contacts"), 1);
    assert_eq!(listing(dir.path()), names(&["case.toml", "case.wav", "case.csv"]));
}

#[test]
fn malformed_scenes_fail_naming_the_key_and_leave_no_output() {
    let cases = bad_scenes();
    assert!(cases.len() >= 60);
    let mut failures = Vec::new();
    for case in &cases {
        // 1. Default output paths beside the scene: nothing may appear.
        let dir = TempDir::new().unwrap();
        let scene = write_scene(dir.path(), "case.toml", &case.text);
        let out = render_cmd(&scene, &["--csv"]);
        // The scene path is random; keep it from matching a needle by accident.
        let stderr = out.stderr.replace(&scene.display().to_string(), "<scene>");
        let mut problems = Vec::new();
        if out.code == 0 {
            problems.push("exit code 0".to_owned());
        }
        if !out.stdout.is_empty() {
            problems.push(format!("stdout not empty: {:?}", out.stdout));
        }
        if !stderr.starts_with("error: <scene>") {
            problems.push("stderr does not start with `error: <scene path>`".to_owned());
        }
        for needle in case.needles {
            if !stderr.contains(needle) {
                problems.push(format!("stderr lacks {needle:?}"));
            }
        }
        if listing(dir.path()) != names(&["case.toml"]) {
            problems.push(format!("files left behind: {:?}", listing(dir.path())));
        }
        if fs::read_to_string(&scene).unwrap() != case.text {
            problems.push("scene file changed".to_owned());
        }

        // 2. Pre-existing outputs at an explicit --out are left byte-identical.
        let wav = dir.path().join("keep.wav");
        let csv = dir.path().join("keep.csv");
        fs::write(&wav, b"old wav bytes").unwrap();
        fs::write(&csv, b"old csv bytes").unwrap();
        let out2 = render_to(&scene, &wav, &["--csv", "--chunk", "0"]);
        if out2.code == 0 {
            problems.push("exit code 0 with --out".to_owned());
        }
        if fs::read(&wav).unwrap() != b"old wav bytes" || fs::read(&csv).unwrap() != b"old csv bytes" {
            problems.push("pre-existing outputs changed".to_owned());
        }
        if listing(dir.path()) != names(&["case.toml", "keep.wav", "keep.csv"]) {
            problems.push(format!("files after the --out run: {:?}", listing(dir.path())));
        }
        if !problems.is_empty() {
            failures.push(format!("{}: {}\n  stderr: {}", case.what, problems.join("; "), stderr.trim_end()));
        }
    }
    assert!(failures.is_empty(), "{} malformed scene(s) mishandled:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn malformed_scenes_fail_in_process_with_a_scene_error() {
    // The library entry point gives a typed scene error, never a panic or a partial render.
    for case in bad_scenes() {
        let dir = TempDir::new().unwrap();
        let scene = write_scene(dir.path(), "case.toml", &case.text);
        let args = RenderArgs { scene: Some(scene), csv: true, ..RenderArgs::default() };
        let mut stdout = Vec::new();
        let err = xtask::render::run(&args, &mut stdout).expect_err(case.what);
        assert!(matches!(err, xtask::render::RenderError::Scene { .. }), "{}: {err:?}", case.what);
        assert!(stdout.is_empty(), "{}", case.what);
        assert_eq!(listing(dir.path()), names(&["case.toml"]), "{}", case.what);
    }
}

// ------------------------------------------------------------------------------------------------
// Output paths: the scene is never an output; outputs are replaced whole or not at all
// ------------------------------------------------------------------------------------------------

/// Check a render was refused, leaving `dir` with exactly `files` and the scene untouched.
fn assert_refused(out: &Outcome, needle: &str, dir: &Path, scene: &Path, scene_text: &str, files: &[&str]) {
    assert_ne!(out.code, 0, "render must be refused");
    assert!(out.stdout.is_empty(), "no summary for a refused render: {:?}", out.stdout);
    assert!(out.stderr.contains(needle), "stderr {:?} lacks {needle:?}", out.stderr);
    assert_eq!(fs::read_to_string(scene).unwrap(), scene_text, "the scene file is unchanged");
    assert_eq!(listing(dir), names(files));
}

#[test]
fn out_pointing_at_the_scene_file_is_refused() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let out = render_to(&scene, &scene, &[]);
    assert_refused(&out, "input file", dir.path(), &scene, BASE, &["case.toml"]);

    // The same file by another spelling.
    let other = dir.path().join(".").join("sub").join("..").join("case.toml");
    fs::create_dir(dir.path().join("sub")).unwrap();
    let out = render_to(&scene, &other, &["--csv"]);
    assert_refused(&out, "input file", dir.path(), &scene, BASE, &["case.toml", "sub"]);
}

#[cfg(unix)]
#[test]
fn out_through_a_symlink_to_the_scene_file_is_refused() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let link = dir.path().join("link.wav");
    std::os::unix::fs::symlink(&scene, &link).unwrap();
    let out = render_to(&scene, &link, &[]);
    assert_refused(&out, "input file", dir.path(), &scene, BASE, &["case.toml", "link.wav"]);
}

/// `--out` through a symbolic link writes the file it names and keeps the link.
#[cfg(unix)]
#[test]
fn out_through_a_symlink_writes_the_file_it_names_and_keeps_the_link() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let (real, link) = (dir.path().join("real.wav"), dir.path().join("link.wav"));
    fs::write(&real, b"old").unwrap();
    std::os::unix::fs::symlink(&real, &link).unwrap();
    let out = render_to(&scene, &link, &[]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(fs::symlink_metadata(&link).unwrap().file_type().is_symlink(), "the link stays a link");
    let (spec, samples) = read_wav(&real);
    assert_eq!((spec.channels, samples.len()), (1, 88), "the file it names holds the render");
}

/// `--out` naming something other than a regular file (a named pipe here; `/dev/null` alike) is
/// written into, not replaced by a regular file: a reader at the pipe's other end gets the WAV,
/// and the pipe is still a pipe.
#[cfg(unix)]
#[test]
fn out_naming_a_pipe_writes_into_it_and_leaves_it_a_pipe() {
    use std::os::unix::fs::FileTypeExt;
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let pipe = dir.path().join("pipe.wav");
    let made = std::process::Command::new("mkfifo").arg(&pipe).status().expect("mkfifo runs");
    assert!(made.success());
    let reader = {
        let pipe = pipe.clone();
        std::thread::spawn(move || fs::read(pipe).expect("the pipe reads"))
    };
    let out = render_to(&scene, &pipe, &[]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    assert!(fs::symlink_metadata(&pipe).unwrap().file_type().is_fifo(), "the pipe stays a pipe");
    let bytes = reader.join().unwrap();
    let file = dir.path().join("file.wav");
    assert_eq!(render_to(&scene, &file, &[]).code, 0);
    assert!(bytes == fs::read(&file).unwrap(), "the reader gets the WAV a file gets ({} bytes)", bytes.len());
}

/// The options that apply to `--midi` alone are refused with a scene file, naming the option,
/// rather than ignored, even at their defaults, as a usage error (exit code 2, as for the
/// parser's own); nothing is written.
#[test]
fn midi_options_with_a_scene_file_are_refused() {
    for extra in [
        &["--preset", "concert-grand"][..],
        &["--mode", "slide"],
        &["--set", "hard=2"],
        &["--rate", "96000"],
        &["--rate", "48000"],
        &["--tail", "5"],
        &["--tail", "2"],
        &["--raw"],
    ] {
        let dir = TempDir::new().unwrap();
        let scene = write_scene(dir.path(), "case.toml", BASE);
        let out = render_to(&scene, &dir.path().join("out.wav"), extra);
        assert_refused(&out, &format!("{} applies to --midi only", extra[0]), dir.path(), &scene, BASE, &["case.toml"]);
        assert_eq!(out.code, 2, "{extra:?}");
    }
}

/// With `--csv`, a CSV that would be the WAV itself is refused and nothing is written: a WAV
/// named `.CSV` (the same file as its `.csv` on a case-insensitive file system), and a `.csv`
/// that is a link to the WAV.
#[test]
fn a_csv_that_would_be_the_wav_itself_is_refused() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let out = render_to(&scene, &dir.path().join("x.CSV"), &["--csv"]);
    assert_refused(&out, "the CSV would replace the WAV", dir.path(), &scene, BASE, &["case.toml"]);
    #[cfg(unix)]
    {
        let (wav, csv) = (dir.path().join("take.wav"), dir.path().join("take.csv"));
        fs::write(&wav, b"mine").unwrap();
        std::os::unix::fs::symlink(&wav, &csv).unwrap();
        let out = render_to(&scene, &wav, &["--csv"]);
        assert_refused(
            &out,
            "the CSV would replace the WAV",
            dir.path(),
            &scene,
            BASE,
            &["case.toml", "take.csv", "take.wav"],
        );
        assert_eq!(fs::read(&wav).unwrap(), b"mine");
    }
}

/// A string with more modes below Nyquist than a string holds (4,096) at the scene's rate, or
/// with none, is an error naming the string and the rate, and what to change: the C4 string
/// made 50 m long at 44.1 kHz, 1 cm long (its fundamental above Nyquist, so it would render
/// silence), and the C4 preset as it is at 500 Hz (no `length` in the file to name). Its
/// parameters are valid; its mode count depends on the rate too.
#[test]
fn a_string_with_too_many_modes_or_none_at_the_scenes_rate_is_a_clear_error() {
    let soft = fs::read_to_string(fig4_path().with_file_name("hammer-c4-soft.toml")).unwrap();
    let longer = |length: &str| edit(&soft, "eta0 = 8.0 ", &format!("length = {length}\neta0 = 8.0 "));
    let cases = [
        (
            longer("50.0"),
            "more than 4096 modes below 22050 Hz, Nyquist at sample_rate = 44100; shorten it, raise its tension or \
             lower sample_rate",
        ),
        (
            longer("0.01"),
            "no mode below 22050 Hz, Nyquist at sample_rate = 44100: it would be silent; lengthen it, lower its \
             tension or raise sample_rate",
        ),
        (edit(&soft, "sample_rate = 44100", "sample_rate = 500"), "no mode below 250 Hz, Nyquist at sample_rate = 500"),
    ];
    for (text, why) in cases {
        let dir = TempDir::new().unwrap();
        let scene = write_scene(dir.path(), "case.toml", &text);
        let result = render_to(&scene, &dir.path().join("out.wav"), &[]);
        assert_eq!(result.code, 1, "{}", result.stderr);
        assert!(result.stderr.contains("string") && result.stderr.contains(why), "{}", result.stderr);
        assert!(!result.stderr.contains("string.length"), "no key the file may lack: {}", result.stderr);
        assert_eq!(listing(dir.path()), names(&["case.toml"]), "nothing written");
    }
}

/// Values of the string scenes beyond reason are refused, naming a key the file gave: a hammer or
/// a slide too light for the floats, the two damping forms mixed (named by the key of the second
/// form that was given), and a hand height or a finger force far beyond any gesture (whose lane
/// would otherwise interpolate out of the floats: −1e308 to 1e308 m gives NaN).
#[test]
fn string_scene_values_beyond_reason_are_refused_naming_a_key_the_file_gave() {
    let soft = fs::read_to_string(fig4_path().with_file_name("hammer-c4-soft.toml")).unwrap();
    let phrase = fs::read_to_string(fig4_path().with_file_name("slide-phrase.toml")).unwrap();
    let height = "points = [[0.0, 3e-3], [0.15, 3e-3], [0.25, -1.5e-3], [2.45, -1.5e-3], [3.0, 1.5e-3]]";
    let cases = [
        (edit(&soft, "velocity = 1.0 ", "mass = 1e-320\nvelocity = 1.0 "), "hammer.mass: must be at least 1e-9 kg"),
        (edit(&phrase, "[control]", "[slide]\nmass = 1e-12\n\n[control]"), "slide.mass: must be at least 1e-9 kg"),
        (edit(&soft, "eta0 = 8.0 ", "eta0 = 8.0\nb3 = 1e-9 "), "string.b3: give damping either"),
        (edit(&phrase, height, "points = [[0.0, -1e308], [1.0, 1e308]]"), "-1e308 m at t = 0 s is beyond ±1 m"),
        (edit(&phrase, "[0.4, 1.5]", "[0.4, 1500.0]"), "1.5e3 N at t = 0.4 s is beyond ±1000 N"),
    ];
    for (text, why) in cases {
        let error = parse_scene(&text).err().map(|e| e.to_string());
        assert!(error.as_deref().is_some_and(|e| e.contains(why)), "{why}: {error:?}");
    }
}

/// A library render given chunk sizes of 0 for ever ends: the sizes are skipped up to as many
/// as there are frames, and the rest is rendered in one call, bit for bit as with no sizes.
#[test]
fn a_render_given_only_chunk_sizes_of_zero_ends_with_the_frames_of_one_call() {
    let scene = parse_scene(&fig4_text()).unwrap();
    let zeros = render(&scene, std::iter::repeat(0)).unwrap();
    let whole = render(&scene, std::iter::empty()).unwrap();
    assert_eq!(zeros.frames.len(), whole.frames.len());
    assert!(zeros.frames.iter().zip(&whole.frames).all(|(a, b)| a.force.to_bits() == b.force.to_bits()));
}

/// An input beyond 16 MiB, a scene file (Fig. 4 with 17 MiB of comments) or a MIDI file, is
/// refused without being read whole, and nothing is written.
#[test]
fn an_input_beyond_sixteen_mebibytes_is_refused() {
    let dir = TempDir::new().unwrap();
    let mut text = fig4_text();
    let comment = format!("# {}\n", "x".repeat(1021));
    text.push_str(&comment.repeat(17 << 10));
    let scene = write_scene(dir.path(), "big.toml", &text);
    let out = render_to(&scene, &dir.path().join("out.wav"), &[]);
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(out.stderr.contains("more than 16777216 bytes (16 MiB)"), "{}", out.stderr);
    let midi = dir.path().join("big.mid");
    fs::write(&midi, vec![0u8; (16 << 20) + 1]).unwrap();
    let out = xtask(&[OsString::from("render"), OsString::from("--midi"), midi.into_os_string()]);
    assert_eq!(out.code, 1, "{}", out.stderr);
    assert!(out.stderr.contains("more than 16777216 bytes (16 MiB)"), "{}", out.stderr);
    assert_eq!(listing(dir.path()), names(&["big.toml", "big.mid"]));
}

/// A preset's contact law serves only its own collider: the C4 preset's felt under a slide and
/// the slide guitar's glass under a hammer are refused as a missing `contact.kappa`, which
/// `[contact]` then gives; each preset still gives its own scene the law.
#[test]
fn a_presets_contact_law_serves_only_its_own_collider() {
    let soft = fs::read_to_string(fig4_path().with_file_name("hammer-c4-soft.toml")).unwrap();
    let phrase = fs::read_to_string(fig4_path().with_file_name("slide-phrase.toml")).unwrap();
    let slide_on_c4 = edit(&phrase, "preset = \"slide-guitar\"", "preset = \"c4\"");
    // The slide guitar's string under the hammer, which the preset does not give.
    let hammer_on_guitar = edit(&soft, "preset = \"c4\"", "preset = \"slide-guitar\"");
    let hammer_on_guitar = edit(&hammer_on_guitar, "velocity = 1.0 ", "mass = 3e-3\nposition = 0.12\nvelocity = 1.0 ");
    for (what, text) in [("a slide on the C4 preset", slide_on_c4), ("a hammer on the slide guitar", hammer_on_guitar)]
    {
        let dir = TempDir::new().unwrap();
        let scene = write_scene(dir.path(), "case.toml", &text);
        let result = render_to(&scene, &dir.path().join("out.wav"), &[]);
        assert_eq!(result.code, 1, "{what}: {}", result.stderr);
        assert!(
            result.stderr.contains("contact.kappa") && result.stderr.contains("missing"),
            "{what}: {}",
            result.stderr
        );
        let given = edit(&text, "[solver]", "[contact]\nkappa = 1e9\nalpha = 1.5\n\n[solver]");
        // (The C4 preset gives no slide or fingers either: those are missing next.)
        let next = parse_scene(&given).err().map(|e| e.to_string());
        assert!(!next.as_deref().is_some_and(|e| e.contains("contact.")), "{what}, its [contact] given: {next:?}");
    }
    assert!(parse_scene(&soft).is_ok() && parse_scene(&phrase).is_ok(), "each preset's own scene takes its law");
}

/// A render whose output is not finite writes nothing and says why: a hammer thrown at 1e200 m/s
/// (its `v_ref` given, so the fit is not sized for it) leaves the floats at once, and a gain of
/// 1e300 on a finite output overflows 32-bit float. An existing output file is left as it was.
#[test]
fn a_render_that_is_not_finite_writes_nothing_and_says_why() {
    let dir = TempDir::new().unwrap();
    let out = dir.path().join("out.wav");
    fs::write(&out, b"kept").unwrap();
    let soft = fs::read_to_string(fig4_path().with_file_name("hammer-c4-soft.toml")).unwrap();
    let thrown =
        edit(&edit(&soft, "velocity = 1.0 ", "velocity = 1e200 "), "segments = 13", "segments = 13\nv_ref = 1.0");
    for (text, why) in [
        (thrown, "beyond what the scheme can simulate"),
        (edit(BASE, "gain = 1.0", "gain = 1e300"), "exceeds 32-bit float"),
    ] {
        let scene = write_scene(dir.path(), "case.toml", &text);
        let result = render_to(&scene, &out, &[]);
        assert_ne!(result.code, 0, "{why}: refused");
        assert!(result.stderr.contains("not finite") && result.stderr.contains(why), "{why}: {}", result.stderr);
        assert_eq!(fs::read(&out).unwrap(), b"kept", "{why}: the existing output is untouched");
    }
}

#[test]
fn default_output_that_would_be_the_scene_is_refused() {
    // A scene file named *.wav: the default WAV path is the scene itself.
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.wav", BASE);
    let out = render_cmd(&scene, &[]);
    assert_refused(&out, "input file", dir.path(), &scene, BASE, &["case.wav"]);

    // A scene file named *.csv and --csv: the CSV path is the scene itself; the WAV is not
    // written either.
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.csv", BASE);
    let out = render_to(&scene, &dir.path().join("case.wav"), &["--csv"]);
    assert_refused(&out, "input file", dir.path(), &scene, BASE, &["case.csv"]);
}

#[test]
fn a_wav_path_ending_in_csv_with_csv_is_refused() {
    // `--out x.csv --csv` would make the CSV overwrite the WAV.
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let out = render_to(&scene, &dir.path().join("x.csv"), &["--csv"]);
    assert_refused(&out, "x.csv", dir.path(), &scene, BASE, &["case.toml"]);
    // Without --csv the same path is an ordinary (oddly named) WAV.
    let out = render_to(&scene, &dir.path().join("x.csv"), &[]);
    assert_eq!(out.code, 0, "{}", out.stderr);
    let (spec, samples) = read_wav(&dir.path().join("x.csv"));
    assert_eq!((spec.channels, samples.len()), (1, 88));
}

#[test]
fn missing_scene_file_is_a_clear_error() {
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("no-such-scene.toml");
    let out = render_cmd(&scene, &["--csv"]);
    assert_eq!(out.code, 1);
    assert!(out.stdout.is_empty());
    assert!(out.stderr.contains("cannot read"), "{}", out.stderr);
    assert!(out.stderr.contains("no-such-scene.toml"), "{}", out.stderr);
    assert!(out.stderr.contains("No such file"), "{}", out.stderr);
    assert!(listing(dir.path()).is_empty());
}

#[test]
fn missing_output_directory_is_an_error_and_writes_nothing() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let out = render_to(&scene, &dir.path().join("nowhere").join("o.wav"), &["--csv"]);
    assert_refused(&out, "does not exist", dir.path(), &scene, BASE, &["case.toml"]);
}

#[test]
fn existing_outputs_survive_a_refused_csv_path() {
    // The WAV path is fine but the CSV path is a directory: the render fails before anything is
    // written, so the old WAV is still there byte for byte.
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let wav = dir.path().join("o.wav");
    fs::write(&wav, b"previous render").unwrap();
    fs::create_dir(dir.path().join("o.csv")).unwrap();
    let out = render_to(&scene, &wav, &["--csv"]);
    assert_refused(&out, "is a directory", dir.path(), &scene, BASE, &["case.toml", "o.wav", "o.csv"]);
    assert_eq!(fs::read(&wav).unwrap(), b"previous render");
    assert!(dir.path().join("o.csv").is_dir());
}

#[test]
fn existing_outputs_are_replaced_by_complete_new_ones() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    // A fresh render elsewhere gives the expected bytes.
    let fresh = TempDir::new().unwrap();
    summary_line(&render_to(&scene, &fresh.path().join("o.wav"), &["--csv"]));
    let want_wav = fs::read(fresh.path().join("o.wav")).unwrap();
    let want_csv = fs::read(fresh.path().join("o.csv")).unwrap();

    // Old outputs, one longer than the new file so a truncation bug would show.
    let wav = dir.path().join("o.wav");
    let csv = dir.path().join("o.csv");
    fs::write(&wav, vec![0xAB; want_wav.len() * 3]).unwrap();
    fs::write(&csv, b"stale").unwrap();
    summary_line(&render_to(&scene, &wav, &["--csv", "--chunk", "0"]));
    assert!(fs::read(&wav).unwrap() == want_wav, "WAV fully replaced");
    assert!(fs::read(&csv).unwrap() == want_csv, "CSV fully replaced");
    // No temporary files left beside them.
    assert_eq!(listing(dir.path()), names(&["case.toml", "o.wav", "o.csv"]));
    // Ordinary file permissions, not the owner-only mode of temporary files.
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        assert_eq!(fs::metadata(&wav).unwrap().permissions().mode() & 0o777, 0o644);
    }
}

#[test]
fn bad_command_lines_are_usage_errors() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), "case.toml", BASE);
    let out = render_cmd(&scene, &["--chunk", "many"]);
    assert_eq!(out.code, 2, "clap usage error: {}", out.stderr);
    assert!(out.stderr.contains("--chunk"), "{}", out.stderr);
    assert!(out.stdout.is_empty());
    let out = render_cmd(&scene, &["--frobnicate"]);
    assert_eq!(out.code, 2);
    assert!(out.stderr.contains("--frobnicate"), "{}", out.stderr);
    assert_eq!(listing(dir.path()), names(&["case.toml"]));
}
