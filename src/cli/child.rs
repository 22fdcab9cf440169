//! `frond child`: a child run of `frond batch` or `frond sweep`. The parent writes the
//! settings it built to standard input ([`ChildRequest`]); the child runs them as `frond lod`
//! or `frond eval --json` would, so its output files and printed lines are theirs.

use anyhow::Result;

use frond_app::child_request::ChildRequest;

/// `frond child` (hidden: only frond starts it).
#[derive(clap::Args, Clone, Debug)]
pub struct ChildArgs {}

impl ChildArgs {
    /// Reads the request from standard input and runs it.
    pub fn run(self) -> Result<()> {
        match ChildRequest::read(std::io::stdin().lock())? {
            ChildRequest::Lod(settings) => super::lod::run_settings(settings, false),
            ChildRequest::Eval(settings) => super::eval::run_settings(&settings, true),
        }
    }
}
