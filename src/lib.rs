//! The `frond` pipeline: each CLI command's work as a library function, so tests can call it.

pub mod cloud_cmd;
pub mod inspect;
pub mod output;
pub mod render_cmd;
