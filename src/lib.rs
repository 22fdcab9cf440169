//! The `frond` pipeline: each CLI command's work as a library function, so tests can call it.

pub mod batch;
pub mod child_job;
pub mod cli;
pub mod cloud_cmd;
pub mod csv_text;
pub mod eval_cmd;
pub mod inspect;
pub mod lod_cmd;
pub mod out_folder;
pub mod output_set;
pub mod render_cmd;
pub mod sweep;
pub mod view_server;
