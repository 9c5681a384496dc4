//! Where the plugin bundles are, and a check that they are there and current (shared by the
//! real-host tests).
//!
//! A bundle that is missing, or older than any file it is built from, fails
//! the test with the command that builds it: testing a stale binary would test other code.
//! `QSA_ALLOW_STALE_BUNDLE=1` skips the age check (when iterating on the tests themselves).

use std::path::{Path, PathBuf};
use std::time::SystemTime;

/// The command that builds the release bundles.
pub const BUILD_RELEASE: &str = "cargo xtask bundle qsa-plugin --release";

/// Set to test a bundle older than the sources.
pub const ALLOW_STALE_ENV: &str = "QSA_ALLOW_STALE_BUNDLE";

/// The workspace root.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).parent().expect("tests/ is inside the workspace").to_path_buf()
}

/// Cargo's target directory.
pub fn target_dir() -> PathBuf {
    std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| workspace_root().join("target"), PathBuf::from)
}

/// Newest modification time of the files under `dir`.
fn newest_under(dir: &Path) -> Option<(SystemTime, PathBuf)> {
    let mut newest: Option<(SystemTime, PathBuf)> = None;
    for entry in std::fs::read_dir(dir).ok()?.flatten() {
        let path = entry.path();
        let candidate = if path.is_dir() {
            newest_under(&path)
        } else {
            entry.metadata().ok().and_then(|m| m.modified().ok()).map(|t| (t, path))
        };
        if let Some((t, p)) = candidate
            && newest.as_ref().is_none_or(|(n, _)| t > *n)
        {
            newest = Some((t, p));
        }
    }
    newest
}

/// `path` if it exists and is newer than everything it is built from ([`BUNDLE_INPUTS`]);
/// otherwise a failure that says to run `build`.
pub fn checked_bundle(path: PathBuf, build: &str) -> PathBuf {
    assert!(
        path.exists(),
        "the plugin bundle {} is missing: run `{build}` first (CI builds it before the tests)",
        path.display()
    );
    if std::env::var_os(ALLOW_STALE_ENV).is_some() {
        return path;
    }
    let built = std::fs::metadata(&path).and_then(|m| m.modified()).expect("bundle modification time");
    let root = workspace_root();
    for input in BUNDLE_INPUTS {
        let input = root.join(input);
        let newest = if input.is_dir() {
            newest_under(&input)
        } else {
            std::fs::metadata(&input).and_then(|m| m.modified()).ok().map(|t| (t, input.clone()))
        };
        let (changed, file) =
            newest.unwrap_or_else(|| panic!("{} is not there to compare the bundle with", input.display()));
        assert!(
            changed <= built,
            "the plugin bundle {} is older than {}: run `{build}` again (or set {ALLOW_STALE_ENV}=1 to test it \
             anyway)",
            path.display(),
            file.display()
        );
    }
    path
}

/// What the bundle is built from: the plugin's and the engine's sources, the factory presets the
/// engine embeds, and the manifests and lock file that pick the code compiled with them.
const BUNDLE_INPUTS: [&str; 7] =
    ["plugin/src", "dsp/src", "presets", "Cargo.toml", "Cargo.lock", "plugin/Cargo.toml", "dsp/Cargo.toml"];
