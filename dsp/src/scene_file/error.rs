//! The error of a scene file that cannot be rendered, naming the key at fault.

use crate::contact::ContactError;

/// A scene file that cannot be rendered.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SceneError {
    /// Not valid TOML, a key of the wrong type, or a key the format does not have.
    #[error("{0}")]
    Syntax(String),
    /// A value out of its domain.
    #[error("{key}: {reason}")]
    Invalid {
        /// Dotted key path, e.g. `mass.mass`.
        key: String,
        /// What is wrong.
        reason: String,
    },
}

impl SceneError {
    pub(crate) fn invalid(key: &str, reason: impl Into<String>) -> Self {
        Self::Invalid { key: key.to_owned(), reason: reason.into() }
    }

    /// Map a contact-parameter error to the scene key it came from (`table.key`).
    pub(crate) fn contact(table: &str, error: ContactError) -> Self {
        match error {
            ContactError::Invalid { key, reason, value } => {
                let key = match key {
                    "segments" | "v_ref" => format!("solver.{key}"),
                    _ => format!("{table}.{key}"),
                };
                Self::Invalid { key, reason: format!("{reason} (got {value})") }
            }
            e @ ContactError::NotConvex { .. } => Self::invalid("solver.segments", e.to_string()),
        }
    }
}
