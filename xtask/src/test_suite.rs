//! `cargo xtask test`: everything the tests need, then every test.
//!
//! 1. the Python virtual environment of the VST3 host test (`target/python-venv/`, see
//!    [`python_venv`]), created and filled only where something is missing;
//! 2. the plugin bundles the real-host tests load: the allocation-checked one, which aborts on any
//!    allocation in `process` (nice-plug arms that check only where debug assertions are on, so it
//!    is built in the test profile and copied to `target/bundled-debug/`), then the release one
//!    (`target/bundled/`). Building it in the test profile lets the test build reuse its
//!    dependencies: CI compiles three profiles, not four;
//! 3. `cargo test --workspace --profile test-release` plus any arguments given. The `test-release`
//!    profile (`Cargo.toml`) is the release build with debug assertions and overflow checks on. The
//!    VST3 host test gets the environment's interpreter (`QSA_PYTHON`).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::python_venv;

/// Arguments of `cargo xtask test`.
#[derive(Debug, clap::Args)]
pub struct TestArgs {
    /// Passed on to `cargo test --workspace --profile test-release`, for example `--no-fail-fast`
    /// or `--test host_vst3`; everything from the first of these on is passed, `--` included.
    #[arg(allow_hyphen_values = true, value_name = "CARGO_TEST_ARGS")]
    pub cargo_test_args: Vec<OsString>,
    /// The test binaries' arguments when they come first, as in `cargo xtask test -- --nocapture`
    /// (clap takes a leading `--` as the end of its own options; it is put back).
    #[arg(last = true, value_name = "TEST_BINARY_ARGS")]
    pub test_binary_args: Vec<OsString>,
}

/// The Cargo profile the tests are built with.
pub const TEST_PROFILE: &str = "test-release";

/// Run `cargo xtask test` (see the module docs).
pub fn run(args: &TestArgs) -> Result<(), String> {
    nice_plug_xtask::chdir_workspace_root().map_err(|e| format!("{e:#}"))?;
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| PathBuf::from("target"), PathBuf::from);
    let python = python_venv::ensure(&target.join(python_venv::VENV_DIR))?;
    let python = std::path::absolute(&python).map_err(|e| format!("{}: {e}", python.display()))?;

    bundle(&["--profile", TEST_PROFILE, "--features", "assert_process_allocs"])?;
    let debug = target.join("bundled-debug");
    if debug.exists() {
        std::fs::remove_dir_all(&debug).map_err(|e| format!("{}: {e}", debug.display()))?;
    }
    copy_dir(&target.join("bundled"), &debug)?;
    bundle(&["--release"])?;

    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let mut tests = Command::new(cargo);
    tests.args(cargo_test_command(args)).env(python_venv::PYTHON_ENV, &python);
    let status = tests.status().map_err(|e| format!("cannot run cargo: {e}"))?;
    if status.success() { Ok(()) } else { Err("tests failed".into()) }
}

/// The arguments of the `cargo test` run: the workspace in the test profile, then `args`.
fn cargo_test_command(args: &TestArgs) -> Vec<OsString> {
    let mut command: Vec<OsString> = ["test", "--workspace", "--profile", TEST_PROFILE].map(Into::into).into();
    command.extend(args.cargo_test_args.iter().cloned());
    if !args.test_binary_args.is_empty() {
        command.push("--".into());
        command.extend(args.test_binary_args.iter().cloned());
    }
    command
}

/// `cargo xtask bundle qsa-plugin ARGS` through nice-plug's bundler (into `target/bundled/`).
fn bundle(args: &[&str]) -> Result<(), String> {
    let args = ["bundle", "qsa-plugin"].iter().chain(args).map(|s| s.to_string());
    nice_plug_xtask::main_with_args("cargo xtask", args).map_err(|e| format!("{e:#}"))
}

/// Copy the directory tree `from` to `to`.
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

#[cfg(test)]
mod tests {
    use clap::Parser;

    use super::cargo_test_command;
    use crate::Cli;

    /// `cargo test`'s arguments after the profile for the command line `cargo xtask test ARGS`.
    fn forwarded(args: &str) -> String {
        let cli = Cli::try_parse_from(["cargo xtask", "test"].into_iter().chain(args.split_whitespace())).unwrap();
        let Cli::Test(test) = cli else { panic!("`test {args}` is not the test command") };
        let command: Vec<String> = cargo_test_command(&test).into_iter().map(|a| a.into_string().unwrap()).collect();
        assert_eq!(command[..4], ["test", "--workspace", "--profile", "test-release"]);
        command[4..].join(" ")
    }

    #[test]
    fn test_arguments_reach_cargo_test_unchanged() {
        for args in [
            "",
            "--no-fail-fast",
            "-- --nocapture",
            "--no-fail-fast -- --nocapture",
            "host_vst3 -- --nocapture",
            "-p qsa-dsp --lib",
            "--test contact_physics --no-fail-fast -- --ignored --exact a -- b",
        ] {
            assert_eq!(forwarded(args), args, "cargo xtask test {args}");
        }
    }
}
