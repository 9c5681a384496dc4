//! Report files: how a finished file gets its permissions (written through a private temporary
//! file, it is made readable like any file written the ordinary way).

/// Make a finished report file readable by everyone, as a file written the ordinary way would be
/// (temporary files are created private).
pub fn make_readable(file: &std::fs::File) -> std::io::Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        file.set_permissions(std::fs::Permissions::from_mode(0o644))?;
    }
    #[cfg(not(unix))]
    let _ = file;
    Ok(())
}
