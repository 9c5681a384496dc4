//! The real `xtask` binary, run as a process: `render` of a good scene succeeds with one JSON
//! line on stdout; a bad scene fails with a non-zero exit code, its error on stderr and no
//! output. Outputs go to temporary directories only.

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use tempfile::TempDir;

fn fig4_text() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../scenes/fig4-mass-barrier.toml");
    fs::read_to_string(path).expect("scenes/fig4-mass-barrier.toml is readable")
}

fn xtask(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_xtask")).args(args).output().expect("the xtask binary runs")
}

fn listing(dir: &Path) -> BTreeSet<String> {
    fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect()
}

fn write_scene(dir: &Path, text: &str) -> PathBuf {
    let scene = dir.join("scene.toml");
    fs::write(&scene, text).unwrap();
    scene
}

#[test]
fn good_scene_exits_zero_with_one_json_line() {
    let dir = TempDir::new().unwrap();
    let scene = write_scene(dir.path(), &fig4_text());
    let wav = dir.path().join("out.wav");
    let out = xtask(&["render".as_ref(), scene.as_os_str(), "--out".as_ref(), wav.as_os_str(), "--csv".as_ref()]);
    let stdout = String::from_utf8(out.stdout).unwrap();
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(0), "stderr: {stderr}");
    assert_eq!(stderr, "");
    assert!(stdout.ends_with('\n'));
    assert_eq!(stdout.lines().count(), 1, "one line on stdout: {stdout:?}");
    let json: serde_json::Value = serde_json::from_str(stdout.trim_end()).expect("the line is JSON");
    assert_eq!(json["scene"], "mass-barrier");
    assert_eq!(json["method"], "qsa");
    assert_eq!(json["samples"], 88);
    assert_eq!(json["contacts"], 1);
    let rebound = json["rebound_velocity"].as_f64().unwrap();
    assert!((rebound + 2.0).abs() <= 1e-9, "rebound {rebound}");

    let names: BTreeSet<String> = ["scene.toml", "out.wav", "out.csv"].iter().map(|s| s.to_string()).collect();
    assert_eq!(listing(dir.path()), names);
    let reader = hound::WavReader::open(&wav).unwrap();
    assert_eq!(reader.spec().sample_format, hound::SampleFormat::Float);
    assert_eq!(reader.spec().bits_per_sample, 32);
    assert_eq!(reader.len(), 88);
    let csv = fs::read_to_string(dir.path().join("out.csv")).unwrap();
    assert!(csv.starts_with("t,u,y,force,energy"), "CSV header: {:?}", csv.lines().next());
    assert_eq!(csv.lines().count(), 89);
}

#[test]
fn bad_scene_exits_non_zero_with_the_error_on_stderr() {
    let dir = TempDir::new().unwrap();
    let text = fig4_text().replace("kappa = 1e8", "kappa = -1e8");
    assert!(text.contains("kappa = -1e8"));
    let scene = write_scene(dir.path(), &text);
    let out = xtask(&["render".as_ref(), scene.as_os_str(), "--csv".as_ref()]);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1), "stderr: {stderr}");
    assert!(out.stdout.is_empty(), "no summary on failure");
    assert!(stderr.starts_with("error: "), "{stderr}");
    assert!(stderr.contains("contact.kappa"), "the error names the key: {stderr}");
    assert!(stderr.contains("> 0"), "the error gives the reason: {stderr}");
    assert_eq!(listing(dir.path()), ["scene.toml".to_string()].into_iter().collect());
    assert_eq!(fs::read_to_string(&scene).unwrap(), text);
}

#[test]
fn missing_scene_exits_non_zero() {
    let dir = TempDir::new().unwrap();
    let scene = dir.path().join("absent.toml");
    let out = xtask(&["render".as_ref(), scene.as_os_str()]);
    let stderr = String::from_utf8(out.stderr).unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(out.stdout.is_empty());
    assert!(stderr.contains("cannot read") && stderr.contains("absent.toml"), "{stderr}");
    assert!(listing(dir.path()).is_empty());
}

/// `examples` and `report` fill folders of their own: pointed at a folder that holds someone
/// else's README (the project's own root, say), each refuses before writing anything, names the
/// folder and says how to write there anyway; the README stays as it was.
#[test]
fn examples_and_report_refuse_a_folder_that_is_not_theirs() {
    for task in [&["examples"][..], &["report", "--from-data"]] {
        let dir = TempDir::new().unwrap();
        let readme = dir.path().join("README.md");
        fs::write(&readme, "# My project\n").unwrap();
        let mut args: Vec<&std::ffi::OsStr> = task.iter().map(|a| a.as_ref()).collect();
        args.extend(["--out".as_ref(), dir.path().as_os_str()]);
        let out = xtask(&args);
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(out.status.code(), Some(1), "{task:?}: {stderr}");
        assert!(stderr.contains(&dir.path().display().to_string()) && stderr.contains("--force"), "{stderr}");
        assert_eq!(fs::read_to_string(&readme).unwrap(), "# My project\n", "{task:?}");
        assert_eq!(listing(dir.path()), ["README.md".to_string()].into_iter().collect());
    }
}
