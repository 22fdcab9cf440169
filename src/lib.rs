//! The `frond` command line: the clap declarations of every command and their dispatch to the
//! application library, [`frond_app`]. Kept a library beside `main.rs` so tests and the fuzz
//! targets parse command lines as the binary does.

pub mod cli;
