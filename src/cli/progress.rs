//! What a command shows while it works (a spinner, a bar over steps, the batch's bars) and how
//! it prints a report: bars only on a terminal, log lines otherwise.

use anyhow::{Context, Result};

use frond_app::batch::BatchProgress;
use frond_app::batch::summary::{BatchSummary, Status, TreeEntry};

/// A spinner with a message on a terminal (nothing otherwise); messages also go to the log.
pub struct Spinner(Option<indicatif::ProgressBar>);

impl Spinner {
    /// Starts the spinner on standard error (hidden when it is not a terminal).
    pub fn start() -> Self {
        Spinner(
            std::io::IsTerminal::is_terminal(&std::io::stderr()).then(|| {
                let b = indicatif::ProgressBar::new_spinner();
                b.enable_steady_tick(std::time::Duration::from_millis(120));
                b
            }),
        )
    }
    /// Shows what is being done now.
    pub fn say(&self, msg: &str) {
        tracing::info!("{msg}");
        if let Some(b) = &self.0 {
            b.set_message(super::terminal::safe(msg).into_owned());
        }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}

/// A progress bar over a known number of steps on a terminal; log lines otherwise.
pub struct Progress(Option<indicatif::ProgressBar>);

impl Progress {
    /// Starts the bar on standard error (hidden when it is not a terminal).
    pub fn start() -> Self {
        Progress(
            std::io::IsTerminal::is_terminal(&std::io::stderr()).then(|| {
                let b = indicatif::ProgressBar::new(0);
                if let Ok(style) = indicatif::ProgressStyle::with_template(
                    "{bar:30} {pos}/{len} {elapsed_precise} (eta {eta}) {msg}",
                ) {
                    b.set_style(style);
                }
                b.enable_steady_tick(std::time::Duration::from_millis(250));
                b
            }),
        )
    }
    /// Shows `done` of `total` steps and what is being done now.
    pub fn step(&self, done: usize, total: usize, msg: &str) {
        tracing::info!("[{done}/{total}] {msg}");
        if let Some(b) = &self.0 {
            b.set_length(total as u64);
            b.set_position(done as u64);
            b.set_message(super::terminal::safe(msg).into_owned());
        }
    }
}

impl Drop for Progress {
    fn drop(&mut self) {
        if let Some(b) = &self.0 {
            b.finish_and_clear();
        }
    }
}

/// The end of `frond batch` and `batch-merge`: the summary (with `--json`) and the count line,
/// an error (non-zero exit) when any tree failed.
pub fn finish_batch(summary: &BatchSummary, dir: &std::path::Path, json: bool) -> Result<()> {
    if json {
        print_json(summary)?;
    }
    let line = summary.counts.line();
    if summary.counts.failed > 0 {
        anyhow::bail!(
            "{line} (reasons in {})",
            dir.join(format!("{}.json", BatchSummary::stem(summary.shard)))
                .display()
        );
    }
    if !json {
        crate::say!("{}: {line}", dir.display());
    }
    Ok(())
}

/// `frond batch` progress: an overall bar plus a spinner per running tree on a terminal, plain
/// log lines otherwise; a failed tree's error line always.
pub struct BatchBar {
    bars: Option<(indicatif::MultiProgress, indicatif::ProgressBar)>,
    running: std::sync::Mutex<Vec<(String, indicatif::ProgressBar)>>,
    done: std::sync::atomic::AtomicUsize,
    total: std::sync::atomic::AtomicUsize,
}

impl BatchBar {
    /// Starts the bar on standard error (hidden when it is not a terminal).
    pub fn start() -> Self {
        let bars = std::io::IsTerminal::is_terminal(&std::io::stderr()).then(|| {
            let multi = indicatif::MultiProgress::new();
            let b = multi.add(indicatif::ProgressBar::new(0));
            if let Ok(style) = indicatif::ProgressStyle::with_template(
                "{bar:30} {pos}/{len} trees {elapsed_precise} (eta {eta}) {msg}",
            ) {
                b.set_style(style);
            }
            b.enable_steady_tick(std::time::Duration::from_millis(250));
            (multi, b)
        });
        BatchBar {
            bars,
            running: std::sync::Mutex::new(Vec::new()),
            done: 0.into(),
            total: 0.into(),
        }
    }

    /// Prints a line above the bars (or plainly).
    pub fn line(&self, text: &str) {
        match &self.bars {
            Some((multi, _)) => {
                let _ = multi.println(super::terminal::safe(text));
            }
            None => crate::say_err!("{text}"),
        }
    }
}

impl BatchProgress for BatchBar {
    fn total(&self, trees: usize) {
        self.total.store(trees, std::sync::atomic::Ordering::SeqCst);
        if let Some((_, b)) = &self.bars {
            b.set_length(trees as u64);
        }
    }

    fn started(&self, tree: &str) {
        tracing::info!("started {tree}");
        if let Some((multi, _)) = &self.bars {
            let s = multi.add(indicatif::ProgressBar::new_spinner());
            s.enable_steady_tick(std::time::Duration::from_millis(120));
            s.set_message(super::terminal::safe(tree).into_owned());
            if let Ok(mut r) = self.running.lock() {
                r.push((tree.to_string(), s));
            }
        }
    }

    fn finished(&self, entry: &TreeEntry) {
        let done = self.done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        let total = self.total.load(std::sync::atomic::Ordering::SeqCst);
        if let Some((multi, b)) = &self.bars {
            b.set_position(done as u64);
            if let Ok(mut r) = self.running.lock()
                && let Some(i) = r.iter().position(|(t, _)| *t == entry.tree)
            {
                let (_, s) = r.remove(i);
                s.finish_and_clear();
                multi.remove(&s);
            }
        }
        match entry.status {
            Status::Failed => self.line(&format!(
                "error: {}: {}",
                entry.tree,
                entry.reason.as_deref().unwrap_or("failed")
            )),
            Status::Built if self.bars.is_none() => self.line(&format!(
                "[{done}/{total}] built {} ({:.1} s)",
                entry.tree, entry.wall_s
            )),
            Status::UpToDate if self.bars.is_none() => {
                self.line(&format!("[{done}/{total}] up to date {}", entry.tree))
            }
            _ => {}
        }
    }
}

impl Drop for BatchBar {
    fn drop(&mut self) {
        if let Some((_, b)) = &self.bars {
            b.finish_and_clear();
        }
    }
}

/// Prints a report as pretty JSON on stdout.
pub fn print_json(report: &impl serde::Serialize) -> Result<()> {
    crate::say!(
        "{}",
        serde_json::to_string_pretty(report).context("serialising the report")?
    );
    Ok(())
}
