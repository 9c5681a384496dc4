//! `cargo xtask`: see the library docs. `bundle`, `bundle-universal` and `known-packages` go to
//! nice-plug's bundler (plugin bundles in `target/bundled/`, names from `bundler.toml`); `test`
//! runs every test (see [`test`]).

use std::path::Path;
use std::process::Command;

/// Commands handled by nice-plug-xtask.
const BUNDLER_COMMANDS: [&str; 3] = ["bundle", "bundle-universal", "known-packages"];

/// Python packages the VST3 host tests use (pedalboard pinned: the tests use its internals).
const PYTHON_PACKAGES: [&str; 4] = ["pedalboard==0.9.26", "mido", "numpy", "pytest"];

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let result = match args.first().map(String::as_str) {
        Some(command) if BUNDLER_COMMANDS.contains(&command) => {
            nice_plug_xtask::main_with_args("cargo xtask", args).map_err(|e| format!("{e:#}"))
        }
        Some("test") => test(&args[1..]),
        _ => {
            let code = xtask::run(args.into_iter().map(Into::into), &mut std::io::stdout(), &mut std::io::stderr());
            std::process::exit(code);
        }
    };
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// `cargo xtask test [cargo test args]`: everything the tests need, then every test.
/// 1. the Python packages of the VST3 host tests, installed with pip if missing;
/// 2. the plugin bundles the real-host tests load: the debug one that aborts on any allocation in
///    `process` (copied to `target/bundled-debug/`), then the release one (`target/bundled/`);
/// 3. `cargo test --workspace --release` (plus any arguments given), requiring the debug bundle.
fn test(extra: &[String]) -> Result<(), String> {
    nice_plug_xtask::chdir_workspace_root().map_err(|e| format!("{e:#}"))?;
    let imports = "import pedalboard, mido, numpy, pytest";
    if !run(Command::new("python3").args(["-c", imports]).stderr(std::process::Stdio::null()))? {
        eprintln!("xtask test: installing the Python packages of the VST3 host tests: {}", PYTHON_PACKAGES.join(" "));
        let mut pip = Command::new("python3");
        pip.args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check"]).args(PYTHON_PACKAGES);
        if !run(&mut pip)? {
            return Err("pip could not install the Python test packages".into());
        }
    }
    let bundle = |extra: &[&str]| {
        let args = ["bundle", "qsa-plugin"].iter().chain(extra).map(|s| s.to_string());
        nice_plug_xtask::main_with_args("cargo xtask", args).map_err(|e| format!("{e:#}"))
    };
    bundle(&["--features", "assert_process_allocs"])?;
    let debug = Path::new("target/bundled-debug");
    if debug.exists() {
        std::fs::remove_dir_all(debug).map_err(|e| format!("{}: {e}", debug.display()))?;
    }
    copy_dir(Path::new("target/bundled"), debug)?;
    bundle(&["--release"])?;
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut tests = Command::new(cargo);
    tests.args(["test", "--workspace", "--release"]).args(extra).env("QSA_REQUIRE_DEBUG_BUNDLE", "1");
    if run(&mut tests)? { Ok(()) } else { Err("tests failed".into()) }
}

fn run(command: &mut Command) -> Result<bool, String> {
    command.status().map(|s| s.success()).map_err(|e| format!("cannot run {:?}: {e}", command.get_program()))
}

fn copy_dir(from: &Path, to: &Path) -> Result<(), String> {
    std::fs::create_dir_all(to).map_err(|e| format!("{}: {e}", to.display()))?;
    for entry in std::fs::read_dir(from).map_err(|e| format!("{}: {e}", from.display()))? {
        let entry = entry.map_err(|e| e.to_string())?;
        let target = to.join(entry.file_name());
        if entry.path().is_dir() {
            copy_dir(&entry.path(), &target)?;
        } else {
            std::fs::copy(entry.path(), &target).map_err(|e| format!("{}: {e}", target.display()))?;
        }
    }
    Ok(())
}
