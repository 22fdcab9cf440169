//! Atomic output: write to a temporary file beside the target, then rename, so a failed run
//! never leaves a partial file.

use std::io::Write;
use std::path::Path;

use anyhow::{Context, Result};

/// Writes `bytes` to `path` atomically.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)
        .with_context(|| format!("{}: cannot create folder", dir.display()))?;
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let tmp = dir.join(format!(".{name}.tmp-{}", std::process::id()));
    let result = (|| -> std::io::Result<()> {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(e).with_context(|| format!("{}: cannot write", path.display()));
    }
    Ok(())
}

/// Writes every `(path, bytes)` atomically, then `report` as pretty JSON at `report_path` (last,
/// so a report on disk means the files it lists are there).
pub fn write_files_and_report(
    files: &[(std::path::PathBuf, Vec<u8>)],
    report_path: &Path,
    report: &impl serde::Serialize,
) -> Result<()> {
    for (p, bytes) in files {
        write_atomic(p, bytes)?;
    }
    let json = serde_json::to_vec_pretty(report)
        .with_context(|| format!("serialising {}", report_path.display()))?;
    write_atomic(report_path, &json)
}
