//! `frond view OUTDIR`: serves an output folder on localhost and opens its preview page.

use std::path::PathBuf;

use anyhow::Result;

use frond_app::view_server::{ViewServer, open_browser};

/// `frond view`.
#[derive(clap::Args, Clone, Debug, PartialEq)]
pub struct ViewArgs {
    /// The output folder of `frond lod`, `frond batch` or `frond sweep`.
    pub folder: PathBuf,
    /// Port on 127.0.0.1 (0: any free port).
    #[arg(long, default_value_t = 8417)]
    pub port: u16,
    /// Print the URL without opening a browser.
    #[arg(long)]
    pub no_open: bool,
}

impl ViewArgs {
    /// Serves until interrupted. The page's URL is the first line on stdout.
    pub fn run(self) -> Result<()> {
        let server = ViewServer::bind(&self.folder, self.port)?;
        let url = server.url()?;
        crate::say!("{url}");
        crate::say_err!(
            "serving {} on {} (read-only; Ctrl-C stops)",
            self.folder.display(),
            server.addr()?
        );
        if !self.no_open && !open_browser(&url) {
            crate::say_err!("no browser could be started: open {url} yourself");
        }
        server.serve()
    }
}
