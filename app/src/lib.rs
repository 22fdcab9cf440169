//! frond's application: each command's work as a library function, called by the thin `frond`
//! binary (which holds only the command line's declarations and dispatch) and by tests.
//!
//! [`lod_settings`] is what one `frond lod` run is asked, clap-free and serialisable: the
//! command line builds it from flags, and `frond batch` and `frond sweep` write it for each
//! child run, which reads it back. Every path the application writes, moves or deletes passes
//! [`out_folder::checked_path`].

pub mod batch;
pub mod child_job;
pub mod child_request;
pub mod cloud_cmd;
pub mod csv_text;
pub mod engine_preset;
pub mod eval_cmd;
pub mod inspect;
pub mod lod_cmd;
pub mod lod_settings;
pub mod out_folder;
pub mod output_set;
pub mod render_cmd;
pub mod sweep;
pub mod view_server;
