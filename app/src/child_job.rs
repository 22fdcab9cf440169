//! One `frond` child process of a sweep or a batch, with a wall-clock limit: a run that
//! crashes, fails or hangs is recorded with its reason and the caller goes on.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};

use crate::child_request::ChildRequest;

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

/// How a child ended, how long it ran and the most memory it held.
#[derive(Clone, Debug)]
pub struct ChildRun {
    /// Whether it finished, failed or was killed at the limit.
    pub end: JobEnd,
    /// Wall-clock time from the start to its end (or its kill at the limit).
    pub wall: Duration,
    /// Peak resident set size (Linux `VmHWM`, sampled while it ran; None elsewhere).
    pub peak_rss: Option<u64>,
}

/// Where and how to start a child.
#[derive(Clone, Debug, Default)]
pub struct ChildSpec<'a> {
    /// Working folder (default: ours).
    pub cwd: Option<&'a Path>,
    /// Extra environment variables.
    pub env: Vec<(String, String)>,
}

/// Runs `exe child` on `request` (written to its standard input) with stdout and stderr in
/// files under `log_dir` (named `<tag>.stdout`, `<tag>.stderr`), killing it once `limit` has
/// passed. Err only when it could not be started.
pub fn run_job(
    exe: &Path,
    request: &ChildRequest,
    log_dir: &Path,
    tag: &str,
    limit: Duration,
) -> Result<JobEnd> {
    Ok(run_child(exe, request, &ChildSpec::default(), log_dir, tag, limit)?.end)
}

/// [`run_job`] with a working folder and environment, reporting wall time and peak memory. On
/// Linux the child is killed when this process dies (`PR_SET_PDEATHSIG`), so a killed batch
/// leaves no orphan writing on.
pub fn run_child(
    exe: &Path,
    request: &ChildRequest,
    spec: &ChildSpec,
    log_dir: &Path,
    tag: &str,
    limit: Duration,
) -> Result<ChildRun> {
    let logs = crate::out_folder::OutFolder::new(log_dir);
    logs.create()?;
    let err_path: PathBuf = logs.path(format!("{tag}.stderr"))?;
    let stdout = logs.create_file(format!("{tag}.stdout"))?;
    let stderr = logs.create_file(format!("{tag}.stderr"))?;
    let start = Instant::now();
    let mut command = Command::new(exe);
    command
        .args(ChildRequest::ARGS)
        .envs(spec.env.iter().map(|(k, v)| (k, v)))
        .stdin(Stdio::piped())
        .stdout(stdout)
        .stderr(stderr);
    if let Some(dir) = spec.cwd {
        command.current_dir(dir);
    }
    die_with_parent(&mut command);
    let mut child = command
        .spawn()
        .with_context(|| format!("cannot start {}", exe.display()))?;
    if let Some(stdin) = child.stdin.take() {
        send_request(stdin, request.to_bytes());
    }
    let mut peak_rss = None;
    let status = loop {
        if let Some(rss) = peak_rss_of(child.id()) {
            peak_rss = Some(peak_rss.map_or(rss, |p: u64| p.max(rss)));
        }
        if let Some(s) = child.try_wait().context("waiting for a child run")? {
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
    let wall = start.elapsed();
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
    Ok(ChildRun {
        end,
        wall,
        peak_rss,
    })
}

/// Writes `bytes` to a child's standard input and closes it, on a thread of its own: a child
/// that does not read (or has died) can neither hold up the wall-clock limit nor, through
/// SIGPIPE, end this process (the binary restores SIGPIPE's default action for its own output);
/// the thread blocks SIGPIPE for itself, so a write to a closed pipe fails with EPIPE instead.
fn send_request(mut stdin: std::process::ChildStdin, bytes: Vec<u8>) {
    std::thread::spawn(move || {
        use std::io::Write;
        block_sigpipe_on_this_thread();
        let _ = stdin.write_all(&bytes);
    });
}

#[cfg(unix)]
fn block_sigpipe_on_this_thread() {
    // SAFETY: builds a signal set on the stack and changes only the calling thread's mask.
    unsafe {
        let mut set = std::mem::MaybeUninit::<libc::sigset_t>::zeroed();
        libc::sigemptyset(set.as_mut_ptr());
        libc::sigaddset(set.as_mut_ptr(), libc::SIGPIPE);
        libc::pthread_sigmask(libc::SIG_BLOCK, set.as_ptr(), std::ptr::null_mut());
    }
}

#[cfg(not(unix))]
fn block_sigpipe_on_this_thread() {}

/// The child's peak resident set so far, from `/proc/<pid>/status` (Linux only).
fn peak_rss_of(pid: u32) -> Option<u64> {
    let text = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = text.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

#[cfg(target_os = "linux")]
fn die_with_parent(command: &mut Command) {
    use std::os::unix::process::CommandExt;
    // SAFETY: prctl is async-signal-safe and touches no memory of the parent; it runs in the
    // forked child before exec.
    let parent = std::process::id();
    unsafe {
        command.pre_exec(move || {
            if libc::prctl(libc::PR_SET_PDEATHSIG, libc::SIGKILL) == -1 {
                return Err(std::io::Error::last_os_error());
            }
            // The parent died between fork and prctl: the signal will never come.
            if libc::getppid() as u32 != parent {
                // (No allocation between fork and exec: a raw OS error.)
                return Err(std::io::Error::from_raw_os_error(libc::ESRCH));
            }
            Ok(())
        });
    }
}

#[cfg(not(target_os = "linux"))]
fn die_with_parent(_command: &mut Command) {}

#[cfg(all(test, unix))]
mod tests {
    use super::*;

    /// An executable shell script of `body` (it gets `child` as its argument and the request
    /// on standard input, as frond would).
    fn script(body: &str) -> (tempfile::TempDir, std::path::PathBuf) {
        use std::os::unix::fs::PermissionsExt;
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("child.sh");
        std::fs::write(&path, format!("#!/bin/sh\n{body}\n")).unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
        (dir, path)
    }

    fn request() -> ChildRequest {
        ChildRequest::Lod(crate::lod_settings::LodSettings::defaults(
            Path::new("t.glb"),
            Path::new("out"),
        ))
    }

    fn sh(body: &str, limit_ms: u64) -> (JobEnd, String) {
        let dir = tempfile::tempdir().unwrap();
        let (_keep, exe) = script(body);
        let end = run_job(
            &exe,
            &request(),
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
        // The child is started as `exe child` with the request on its standard input.
        let (end, out) = sh("echo \"$1\"; cat", 5000);
        assert_eq!(end, JobEnd::Done);
        let (arg, json) = out.split_once('\n').unwrap();
        assert_eq!(arg, "child");
        assert_eq!(ChildRequest::read(json.as_bytes()).unwrap(), request());
        assert_eq!(
            sh("echo first >&2; echo 'error: bad tree' >&2; exit 3", 5000).0,
            JobEnd::Failed("exit 3: error: bad tree".into())
        );
        assert_eq!(
            sh("sleep 5", 200).0,
            JobEnd::TimedOut(Duration::from_millis(200))
        );
    }

    #[cfg(target_os = "linux")]
    #[test]
    fn working_folder_environment_and_peak_memory() {
        let dir = tempfile::tempdir().unwrap();
        let spec = ChildSpec {
            cwd: Some(dir.path()),
            env: vec![("FROND_T".into(), "xyz".into())],
        };
        // Holds ~64 MB in a shell variable for a moment.
        let (_keep, exe) =
            script("pwd; echo $FROND_T; x=$(head -c 64000000 /dev/zero | tr '\\0' a); sleep 0.3");
        let run = run_child(
            &exe,
            &request(),
            &spec,
            dir.path(),
            "t",
            Duration::from_secs(30),
        )
        .unwrap();
        assert_eq!(run.end, JobEnd::Done);
        let out = std::fs::read_to_string(dir.path().join("t.stdout")).unwrap();
        let canonical = std::fs::canonicalize(dir.path()).unwrap();
        assert_eq!(out, format!("{}\nxyz\n", canonical.display()));
        let peak = run.peak_rss.expect("peak memory on Linux");
        assert!(peak > 60_000_000, "{peak}");
        assert!(run.wall >= Duration::from_millis(300));
    }
}
