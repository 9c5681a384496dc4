//! The bundled VST3 plugin in a real host: runs the pedalboard tests
//! (`PYTHON -m pytest -q tests/hosts/test_vst3.py`, see that file for what they check) from the
//! workspace root, and fails with pytest's output if they fail. It first writes the factory
//! presets as VST3 preset files (`xtask::presets`) into `target/vst3-presets-test/` for them.
//!
//! `PYTHON` is the interpreter named by `QSA_PYTHON` (`cargo xtask test` passes the one of its
//! virtual environment `target/python-venv/`), else that environment's interpreter if it exists,
//! else `python3`. It needs pedalboard 0.9.26, mido, numpy and pytest (`cargo xtask test` installs
//! them into the environment), and the test needs the release bundle
//! (`cargo xtask bundle qsa-plugin --release`); without either it fails and says so.
//!
//! Platforms: the plugin library is looked up in the bundle where nice-plug's bundler puts it on
//! Linux (x86, x86_64, aarch64, riscv64), macOS and Windows (x86, x86_64, aarch64); on any other
//! target the test prints why and returns without running pytest. CI runs it on Linux x86_64, and
//! elsewhere it also needs a pedalboard 0.9.26 wheel for the platform.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use xtask::python_venv::{PEDALBOARD_VERSION, PYTHON_ENV, VENV_DIR, venv_python};

#[path = "support/bundle.rs"]
mod bundle;
use bundle::{BUILD_RELEASE, checked_bundle, target_dir, workspace_root};

/// The pytest file, relative to the workspace root.
const SCRIPT: &str = "tests/hosts/test_vst3.py";

/// The plugin library inside the VST3 bundle `vst3` as nice-plug's bundler lays it out for this
/// target, or why there is none.
fn vst3_library(vst3: &Path) -> Result<PathBuf, String> {
    use std::env::consts::{ARCH, OS};
    let (folder, file) = match (OS, ARCH) {
        ("linux", "x86") => ("i386-linux".to_owned(), "QSA Strings.so"),
        ("linux", "x86_64" | "aarch64" | "riscv64") => (format!("{ARCH}-linux"), "QSA Strings.so"),
        ("macos", _) => ("MacOS".to_owned(), "QSA Strings"),
        ("windows", "x86" | "x86_64") => (format!("{ARCH}-win"), "QSA Strings.vst3"),
        ("windows", "aarch64") => ("arm_64-win".to_owned(), "QSA Strings.vst3"),
        _ => return Err(format!("nice-plug's bundler has no VST3 bundle layout for {ARCH} {OS}")),
    };
    Ok(vst3.join("Contents").join(folder).join(file))
}

/// The Python interpreter that runs pytest (see the module docs).
fn python() -> PathBuf {
    if let Some(python) = std::env::var_os(PYTHON_ENV) {
        return python.into();
    }
    let venv = venv_python(&target_dir().join(VENV_DIR));
    if venv.exists() { venv } else { "python3".into() }
}

#[test]
fn pedalboard_plays_the_vst3() {
    let vst3 = target_dir().join("bundled/QSA Strings.vst3");
    let library = match vst3_library(&vst3) {
        Ok(library) => library,
        Err(why) => {
            println!("skipped: {why}");
            return;
        }
    };
    checked_bundle(library, BUILD_RELEASE);
    let python = python();
    let install = format!(
        "cargo xtask test installs them into target/{VENV_DIR}; or {} -m pip install pedalboard=={PEDALBOARD_VERSION} \
         mido numpy pytest",
        python.display()
    );
    let presets = target_dir().join("vst3-presets-test");
    let _ = std::fs::remove_dir_all(&presets);
    let factory = qsa_dsp::instrument::load_factory_presets().expect("the factory presets parse");
    xtask::presets::write_vst3_presets(&factory, &presets, false).expect("the preset files are written");
    let start = Instant::now();
    let output = Command::new(&python)
        .args(["-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", SCRIPT])
        .current_dir(workspace_root())
        .env("QSA_VST3_BUNDLE", &vst3)
        .env("QSA_VST3_PRESETS", &presets)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .unwrap_or_else(|e| panic!("cannot run {} ({e}): install Python 3 ({install})", python.display()));
    let (stdout, stderr) = (String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    println!("{} ran pytest in {:.1} s\n{stdout}{stderr}", python.display(), start.elapsed().as_secs_f64());
    assert!(
        output.status.success(),
        "pytest failed ({}); if a module is missing: {install}\n--- stdout\n{stdout}\n--- stderr\n{stderr}",
        output.status
    );
    let script = std::fs::read_to_string(workspace_root().join(SCRIPT)).expect("the pytest file is readable");
    let tests = script.lines().filter(|l| l.starts_with("def test_")).count();
    assert!(
        stdout.lines().any(|l| l.starts_with(&format!("{tests} passed"))),
        "pytest did not pass all {tests} tests of {SCRIPT}:\n{stdout}"
    );
}
