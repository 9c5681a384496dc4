//! Folders a task fills with files of its own (`examples`, `report`): it writes into a folder that
//! is new, empty, or already its own, and into any other only when told to (`--force`), so that
//! `--out` given by mistake never replaces what someone else wrote.

use std::path::Path;

/// Name of the file that marks a folder as a task's own: the task writes it with `title` as its
/// first line.
pub const README: &str = "README.md";

/// Claim `dir` for `task` (its command name): yes when `dir` does not exist, holds nothing but
/// hidden files (`.gitkeep`, `.DS_Store`), or holds a [`README`] whose first line is `title`, or
/// when `force`; else an error naming the folder and what would be replaced. A folder claimed
/// without a README gets one with the title at once (made if missing), so that a run stopped
/// before its end leaves a folder the next run takes as the task's own: a claimed folder exists.
pub fn claim(dir: &Path, task: &str, title: &str, force: bool) -> Result<(), String> {
    let readme = dir.join(README);
    let first_line = std::fs::read_to_string(&readme).ok().and_then(|t| t.lines().next().map(str::to_owned));
    if first_line.as_deref() == Some(title) {
        return Ok(());
    }
    let io = |e: std::io::Error| format!("{}: {e}", dir.display());
    let visible = |entries: std::fs::ReadDir| {
        entries.filter_map(Result::ok).any(|e| !e.file_name().to_string_lossy().starts_with('.'))
    };
    if force || !dir.exists() || !visible(std::fs::read_dir(dir).map_err(io)?) {
        if first_line.is_none() {
            std::fs::create_dir_all(dir).map_err(io)?;
            std::fs::write(&readme, format!("{title}\n\nBeing written by `cargo xtask {task}`.\n")).map_err(io)?;
        }
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

    /// A new, empty or own folder is claimed, and marked as the task's own by a README with its
    /// title when it has none (so that a run stopped midway leaves it claimable); a folder
    /// holding someone else's README, or files and no README, is refused with its name, unless
    /// forced; a refused folder is left as it was.
    #[test]
    fn a_task_claims_only_new_empty_or_its_own_folders() {
        let dir = tempfile::TempDir::new().unwrap();
        let title = "# Audio examples";
        let claim = |path: &Path, force| claim(path, "examples", title, force);
        let new = dir.path().join("new");
        assert_eq!(claim(&new, false), Ok(()));
        std::fs::write(new.join("concert-grand.wav"), b"half a run").unwrap();
        assert_eq!(claim(&new, false), Ok(()), "a run stopped midway leaves the folder the task's");
        let hidden = dir.path().join("hidden");
        std::fs::create_dir(&hidden).unwrap();
        std::fs::write(hidden.join(".gitkeep"), b"").unwrap();
        assert_eq!(claim(&hidden, false), Ok(()));
        let dir = tempfile::TempDir::new().unwrap();
        std::fs::write(dir.path().join("take.wav"), b"mine").unwrap();
        let refused = claim(dir.path(), false).unwrap_err();
        assert!(refused.contains(&dir.path().display().to_string()) && refused.contains("--force"), "{refused}");
        std::fs::write(dir.path().join(README), "# My project\n").unwrap();
        assert!(claim(dir.path(), false).unwrap_err().contains("is not one `cargo xtask examples` wrote"));
        assert_eq!(std::fs::read_to_string(dir.path().join(README)).unwrap(), "# My project\n");
        assert_eq!(claim(dir.path(), true), Ok(()));
        assert_eq!(std::fs::read_to_string(dir.path().join(README)).unwrap(), "# My project\n", "replaced at the end");
        std::fs::write(dir.path().join(README), format!("{title}\n\nA table.\n")).unwrap();
        assert_eq!(claim(dir.path(), false), Ok(()));
        assert_eq!(std::fs::read(dir.path().join("take.wav")).unwrap(), b"mine");
    }
}
