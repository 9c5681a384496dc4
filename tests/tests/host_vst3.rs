//! The bundled VST3 plugin in a real host: runs the pedalboard tests
//! (`python3 -m pytest -q tests/hosts/test_vst3.py`, see that file for what they check) from the
//! workspace root, and fails with pytest's output if they fail.
//!
//! Needs `python3 -m pip install pedalboard==0.9.26 mido numpy pytest` (`.ci/run` installs them)
//! and the release bundle (`cargo xtask bundle qsa-plugin --release`); without either the test
//! fails and says so.

use std::process::Command;
use std::time::Instant;

#[path = "support/bundle.rs"]
mod bundle;
use bundle::{BUILD_RELEASE, checked_bundle, target_dir, workspace_root};

#[test]
fn pedalboard_plays_the_vst3() {
    let vst3 = target_dir().join("bundled/QSA Strings.vst3");
    checked_bundle(vst3.join("Contents/x86_64-linux/QSA Strings.so"), BUILD_RELEASE);
    let start = Instant::now();
    let output = Command::new("python3")
        .args(["-m", "pytest", "-q", "-s", "-p", "no:cacheprovider", "tests/hosts/test_vst3.py"])
        .current_dir(workspace_root())
        .env("QSA_VST3_BUNDLE", &vst3)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .output()
        .expect("python3 runs (install Python 3 with pedalboard, mido, numpy and pytest)");
    let (stdout, stderr) = (String::from_utf8_lossy(&output.stdout), String::from_utf8_lossy(&output.stderr));
    println!("pytest ran {:.1} s\n{stdout}{stderr}", start.elapsed().as_secs_f64());
    assert!(
        output.status.success(),
        "pytest failed ({}); if a module is missing: python3 -m pip install pedalboard==0.9.26 mido numpy pytest\n\
         --- stdout\n{stdout}\n--- stderr\n{stderr}",
        output.status
    );
    assert!(stdout.contains("5 passed"), "pytest did not run the 5 VST3 tests:\n{stdout}");
}
