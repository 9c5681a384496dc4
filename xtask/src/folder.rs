//! Folders a task fills with files of its own (`examples`, `report`): it writes into a folder that
//! is new, empty, or already its own, and into any other only when told to (`--force`), so that
//! `--out` given by mistake never replaces what someone else wrote.

use std::path::Path;

/// Name of the file that marks a folder as a task's own: the task writes it with `title` as its
/// first line.
pub const README: &str = "README.md";

/// Whether `task` (its command name) may write into `dir`: yes when `dir` does not exist, is an
/// empty folder, or holds a [`README`] whose first line is `title`, or when `force`; else an error
/// naming the folder and what would be replaced.
pub fn claim(dir: &Path, task: &str, title: &str, force: bool) -> Result<(), String> {
    if force || !dir.exists() {
        return Ok(());
    }
    let mut entries = std::fs::read_dir(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    if entries.next().is_none() {
        return Ok(());
    }
    let readme = dir.join(README);
    let first_line = std::fs::read_to_string(&readme).ok().and_then(|t| t.lines().next().map(str::to_owned));
    if first_line.as_deref() == Some(title) {
        return Ok(());
    }
    let why = match first_line {
        Some(_) => format!("its {README} is not one `cargo xtask {task}` wrote (that begins `{title}`)"),
        None => format!("it holds files and no {README} of `cargo xtask {task}`"),
    };
    Err(format!(
        "{}: {why}, so its files could be someone else's; give a new or empty folder, or --force to write there \
         anyway (replacing {README} and any file of the same name)",
        dir.display()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A new, empty or own folder is claimed; a folder holding someone else's README, or files
    /// and no README, is refused with its name, unless forced; nothing is written either way.
    #[test]
    fn a_task_claims_only_new_empty_or_its_own_folders() {
        let dir = tempfile::TempDir::new().unwrap();
        let title = "# Audio examples";
        let claim = |path: &Path, force| claim(path, "examples", title, force);
        assert_eq!(claim(&dir.path().join("new"), false), Ok(()));
        assert_eq!(claim(dir.path(), false), Ok(()));
        std::fs::write(dir.path().join("take.wav"), b"mine").unwrap();
        let refused = claim(dir.path(), false).unwrap_err();
        assert!(refused.contains(&dir.path().display().to_string()) && refused.contains("--force"), "{refused}");
        std::fs::write(dir.path().join(README), "# My project\n").unwrap();
        assert!(claim(dir.path(), false).unwrap_err().contains("is not one `cargo xtask examples` wrote"));
        assert_eq!(claim(dir.path(), true), Ok(()));
        std::fs::write(dir.path().join(README), format!("{title}\n\nA table.\n")).unwrap();
        assert_eq!(claim(dir.path(), false), Ok(()));
        assert_eq!(std::fs::read(dir.path().join("take.wav")).unwrap(), b"mine");
    }
}
