//! One `frond` child process of a sweep, with a wall-clock limit: a run that crashes, fails or
//! hangs is recorded with its reason and the sweep goes on.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};

/// How a child ended.
#[derive(Clone, Debug, PartialEq)]
pub enum JobEnd {
    /// Exit code 0 (its standard output is in `<tag>.stdout`).
    Done,
    /// A non-zero exit or a signal; the last line of its standard error.
    Failed(String),
    /// Killed at the limit.
    TimedOut(Duration),
}

/// Runs `exe args…` with stdout and stderr in files under `log_dir` (named `<tag>.stdout`,
/// `<tag>.stderr`), killing it once `limit` has passed. Err only when it could not be started.
pub fn run_job(
    exe: &Path,
    args: &[String],
    log_dir: &Path,
    tag: &str,
    limit: Duration,
) -> Result<JobEnd> {
    std::fs::create_dir_all(log_dir)
        .with_context(|| format!("{}: cannot create folder", log_dir.display()))?;
    let out_path: PathBuf = log_dir.join(format!("{tag}.stdout"));
    let err_path: PathBuf = log_dir.join(format!("{tag}.stderr"));
    let stdout = std::fs::File::create(&out_path)
        .with_context(|| format!("{}: cannot create", out_path.display()))?;
    let stderr = std::fs::File::create(&err_path)
        .with_context(|| format!("{}: cannot create", err_path.display()))?;
    let start = Instant::now();
    let mut child = Command::new(exe)
        .args(args)
        .stdin(Stdio::null())
        .stdout(stdout)
        .stderr(stderr)
        .spawn()
        .with_context(|| format!("cannot start {}", exe.display()))?;
    let status = loop {
        if let Some(s) = child.try_wait().context("waiting for a sweep run")? {
            break Some(s);
        }
        if start.elapsed() >= limit {
            // Already exited between the two calls is fine: kill then only reaps.
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(20));
    };
    let end = match status {
        None => JobEnd::TimedOut(limit),
        Some(s) if s.success() => JobEnd::Done,
        Some(s) => {
            let text = std::fs::read_to_string(&err_path).unwrap_or_default();
            let last = text
                .lines()
                .rev()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("")
                .trim()
                .to_string();
            JobEnd::Failed(match s.code() {
                Some(c) if !last.is_empty() => format!("exit {c}: {last}"),
                Some(c) => format!("exit {c} with nothing on stderr"),
                None => format!("killed by a signal ({s}) {last}")
                    .trim()
                    .to_string(),
            })
        }
    };
    Ok(end)
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    fn sh(script: &str, limit_ms: u64) -> (JobEnd, String) {
        let dir = tempfile::tempdir().unwrap();
        let end = run_job(
            Path::new("/bin/sh"),
            &["-c".into(), script.into()],
            dir.path(),
            "t",
            Duration::from_millis(limit_ms),
        )
        .unwrap();
        let out = std::fs::read_to_string(dir.path().join("t.stdout")).unwrap();
        (end, out)
    }

    #[test]
    fn output_failure_and_timeout() {
        assert_eq!(sh("echo hi", 5000), (JobEnd::Done, "hi\n".to_string()));
        assert_eq!(
            sh("echo first >&2; echo 'error: bad tree' >&2; exit 3", 5000).0,
            JobEnd::Failed("exit 3: error: bad tree".into())
        );
        assert_eq!(
            sh("sleep 5", 200).0,
            JobEnd::TimedOut(Duration::from_millis(200))
        );
    }
}
