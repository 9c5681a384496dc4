//! The Python environment of the VST3 host test (`tests/hosts/test_vst3.py`): a virtual
//! environment in `target/python-venv/` holding pedalboard (pinned: the test uses internals of its
//! Python layer), mido, numpy and pytest.
//!
//! A virtual environment rather than `pip install` into the system's Python, which Debian and
//! Ubuntu refuse (PEP 668, "externally-managed-environment"). [`ensure`] makes it with
//! `python3 -m venv` when it is missing or has no pip, and runs pip only when a package is missing
//! or pedalboard is not the pinned version. The test reads the interpreter from [`PYTHON_ENV`];
//! without it, it uses this environment if it exists and `python3` otherwise.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

/// The pedalboard version the VST3 host test is written against.
pub const PEDALBOARD_VERSION: &str = "0.9.26";

/// The other Python packages of the VST3 host test (any version).
const OTHER_PACKAGES: [&str; 3] = ["mido", "numpy", "pytest"];

/// Environment variable naming the Python interpreter the VST3 host test runs pytest with.
pub const PYTHON_ENV: &str = "QSA_PYTHON";

/// The virtual environment's directory inside Cargo's target directory.
pub const VENV_DIR: &str = "python-venv";

/// What to install on Debian and Ubuntu when Python or its `venv` module is missing.
const DEBIAN_HINT: &str = "on Debian and Ubuntu: apt-get install python3 python3-venv";

/// The interpreter of the virtual environment at `venv`.
pub fn venv_python(venv: &Path) -> PathBuf {
    if cfg!(windows) { venv.join("Scripts").join("python.exe") } else { venv.join("bin").join("python") }
}

/// Make the virtual environment at `venv` hold every package of the VST3 host test, creating it
/// and running pip only for what is missing. Returns its interpreter.
pub fn ensure(venv: &Path) -> Result<PathBuf, String> {
    let python = venv_python(venv);
    if has_packages(&python) {
        return Ok(python);
    }
    if !succeeds(Command::new(&python).args(["-m", "pip", "--version"])) {
        create(venv)?;
    }
    let packages: Vec<String> =
        std::iter::once(format!("pedalboard=={PEDALBOARD_VERSION}")).chain(OTHER_PACKAGES.map(String::from)).collect();
    eprintln!("xtask test: installing {} into {}", packages.join(" "), venv.display());
    let status = Command::new(&python)
        .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check"])
        .args(&packages)
        .status()
        .map_err(|e| format!("cannot run {}: {e}", python.display()))?;
    if !status.success() {
        return Err(format!("pip could not install {} into {} ({status})", packages.join(" "), venv.display()));
    }
    if !has_packages(&python) {
        return Err(format!("{} still lacks a package after pip install {}", venv.display(), packages.join(" ")));
    }
    Ok(python)
}

/// Whether `python` imports every package, pedalboard at the pinned version.
fn has_packages(python: &Path) -> bool {
    let check = format!(
        "import importlib.metadata, {}, pedalboard\nassert importlib.metadata.version('pedalboard') == \
         '{PEDALBOARD_VERSION}'",
        OTHER_PACKAGES.join(", ")
    );
    succeeds(Command::new(python).args(["-c", &check]))
}

/// A fresh virtual environment at `venv` (replacing a half-made one: `python3 -m venv` without
/// `ensurepip` leaves an environment without pip), made by the `python3` on the `PATH`.
fn create(venv: &Path) -> Result<(), String> {
    if !succeeds(Command::new("python3").arg("--version")) {
        return Err(format!("python3 is missing: the VST3 host test needs Python 3 with venv ({DEBIAN_HINT})"));
    }
    if venv.exists() {
        std::fs::remove_dir_all(venv).map_err(|e| format!("{}: {e}", venv.display()))?;
    }
    eprintln!("xtask test: creating the Python virtual environment {}", venv.display());
    let output = Command::new("python3")
        .args(["-m", "venv"])
        .arg(venv)
        .output()
        .map_err(|e| format!("cannot run python3: {e}"))?;
    if !output.status.success() {
        return Err(format!(
            "`python3 -m venv {}` failed; Python's venv module or ensurepip is missing ({DEBIAN_HINT}):\n{}",
            venv.display(),
            String::from_utf8_lossy(&output.stdout) + String::from_utf8_lossy(&output.stderr)
        ));
    }
    Ok(())
}

/// Whether `command` runs and exits successfully (its output discarded).
fn succeeds(command: &mut Command) -> bool {
    command.stdout(Stdio::null()).stderr(Stdio::null()).status().is_ok_and(|s| s.success())
}
