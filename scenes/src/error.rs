//! The error of a scene: the file, a position where one is known, and the problem.

/// A scene error: the file, a position where one is known, and the problem.
#[derive(Debug, thiserror::Error)]
#[error("{file}{}: {message}", at.map(|(l, c)| format!(":{l}:{c}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file.
    pub file: String,
    /// 1-based line and column.
    pub at: Option<(usize, usize)>,
    /// What is wrong.
    pub message: String,
}
