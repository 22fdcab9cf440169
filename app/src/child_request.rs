//! What a child run of `frond batch` or `frond sweep` is asked: the parent writes the settings
//! it built to the child's standard input, the child (`frond child`) reads them back and runs
//! them.
//! Children never have their options rebuilt as command-line flags, so a setting has one
//! spelling (its field) and the parent and child cannot disagree about a default.

use std::io::Read;

use anyhow::{Context, Result};
use serde::{Deserialize, Serialize};

use crate::eval_cmd::EvalSettings;
use crate::lod_settings::LodSettings;

/// Largest request file a child reads.
const MAX_REQUEST_BYTES: u64 = 1 << 20;

/// One child run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ChildRequest {
    /// Build a LOD chain (`frond lod`); the report is written into the output folder.
    Lod(LodSettings),
    /// Evaluate a candidate (`frond eval --json`); the report is printed to stdout.
    Eval(EvalSettings),
}

impl ChildRequest {
    /// The child's command line after the executable; the request comes on its standard input.
    pub const ARGS: &'static [&'static str] = &["child"];

    /// The request as the child reads it (JSON).
    pub fn to_bytes(&self) -> Vec<u8> {
        // Plain fields, strings and numbers: serialising cannot fail.
        serde_json::to_vec_pretty(self).unwrap_or_default()
    }

    /// Reads a request from `input` (a child's standard input), at most 1 MiB.
    pub fn read(input: impl Read) -> Result<ChildRequest> {
        let mut bytes = Vec::new();
        input
            .take(MAX_REQUEST_BYTES + 1)
            .read_to_end(&mut bytes)
            .context("reading the child request")?;
        if bytes.len() as u64 > MAX_REQUEST_BYTES {
            anyhow::bail!("the child request is over {MAX_REQUEST_BYTES} bytes");
        }
        serde_json::from_slice(&bytes).context("not a frond child request")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    use std::path::Path;

    #[test]
    fn a_request_reads_back_as_written() {
        let mut lod = LodSettings::defaults(Path::new("/trees/t.glb"), Path::new("."));
        lod.lods = vec![300.0, 75.0];
        lod.measure = false;
        let mut eval = EvalSettings::defaults(Path::new("/trees/t.glb"), Path::new("t_LOD1.glb"));
        eval.screen_height = 300.0;
        for req in [ChildRequest::Lod(lod), ChildRequest::Eval(eval)] {
            assert_eq!(ChildRequest::read(&req.to_bytes()[..]).unwrap(), req);
        }
        let huge = vec![b' '; (MAX_REQUEST_BYTES + 1) as usize];
        assert!(ChildRequest::read(&huge[..]).is_err());
    }
}
