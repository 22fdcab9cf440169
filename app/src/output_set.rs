//! Output sets: every file one `frond lod` (or `frond cloud`) run writes for one tree, installed
//! into the output folder as a whole, so that a killed, failed or disk-full run never leaves a
//! partial or mixed set.
//!
//! How (the rule tested in `tests/output_set.rs`: after a kill at any point, the folder holds the
//! complete old set or the complete new set, plus files frond never wrote, untouched):
//!
//! 1. [`OutputSet::prepare`], before any work: refuses an output folder that is a system root or
//!    is the input file; creates the folder if needed and a staging folder
//!    `.frond-staging-<name>%<pid>` inside it (so an unwritable folder fails now, not after the
//!    build); finishes or clears what an earlier, killed run of the same tree left (see 4);
//!    refuses to start while another live run stages the same tree there.
//! 2. [`OutputSet::stage`]: each file is written into the staging folder. A failure (disk full)
//!    removes the staging folder: the old set was never touched.
//! 3. [`OutputSet::commit`]: the report is staged last, then the journal
//!    (`frond-commit.json`: the files to install and the old files to remove) is written
//!    atomically. That rename is the commit point. Installing then: the old report is removed
//!    first (a folder whose report is missing is mid-install), then the old set's files that the
//!    new set does not have, then each new file is renamed into place (same file system, so each
//!    rename is atomic), the report last. A reader that trusts the report never sees a mix.
//! 4. A run killed after the commit point leaves the journal: the next run of that tree into that
//!    folder rolls it forward before it starts (the renames are idempotent). A run killed before
//!    it leaves a staging folder without a journal, which the next run deletes; the old set was
//!    never touched.
//!
//! Ownership: a file belongs to this tree's previous set when that set's report
//! (`<name>_report.json`, or `report.json` of frond before 0.2 with the same `name`) lists it.
//! A file in the way that no report of this tree lists is never replaced: the run is refused,
//! naming it. Files listed by another tree's report in the same folder (the reference shaders
//! under `shaders/`, identical for every tree) may be replaced by the same bytes but are never
//! deleted while that report lists them.
//!
//! Fault injection for the tests: `FROND_FAULT=abort-after:K` aborts the process (as `kill -9`
//! would: no destructor runs) after the K-th file operation of the set (stage, journal, removal or
//! rename, counted from 1), `FROND_FAULT=fail-after:K` makes the next one fail as a full disk
//! would.

use std::collections::BTreeSet;
use std::io::Write;
use std::path::{Component, Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::out_folder::{OutFolder, checked_path};

/// Prefix of staging folders inside an output folder.
pub const STAGING_PREFIX: &str = ".frond-staging-";
/// The journal that marks a staged set as committed.
const JOURNAL: &str = "frond-commit.json";

/// Folders an output set is never written into (a typo such as `-o /` would otherwise fill
/// them).
const SYSTEM_ROOTS: &[&str] = &[
    "/", "/bin", "/boot", "/dev", "/etc", "/lib", "/lib32", "/lib64", "/proc", "/root", "/run",
    "/sbin", "/sys", "/usr", "/var",
];

/// What `FROND_FAULT` asks for (tests only; see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Fault {
    None,
    AbortAfter(usize),
    FailAfter(usize),
}

impl Fault {
    fn from_env() -> Fault {
        let Ok(v) = std::env::var("FROND_FAULT") else {
            return Fault::None;
        };
        let parse = |s: &str| s.trim().parse::<usize>().ok();
        if let Some(k) = v.strip_prefix("abort-after:").and_then(parse) {
            Fault::AbortAfter(k)
        } else if let Some(k) = v.strip_prefix("fail-after:").and_then(parse) {
            Fault::FailAfter(k)
        } else {
            tracing::warn!("FROND_FAULT={v} not understood (abort-after:K or fail-after:K)");
            Fault::None
        }
    }
}

/// The journal: what installing a committed set does.
#[derive(Serialize, Deserialize, Debug)]
struct Journal {
    /// Files to rename from the staging folder into the output folder, the report last.
    install: Vec<String>,
    /// Old files to delete first (the old report first).
    remove: Vec<String>,
}

/// The files of one tree's run, staged and then installed together (see the module doc).
pub struct OutputSet {
    dir: OutFolder,
    name: String,
    report: String,
    /// The staging folder's name inside `dir`.
    staging: String,
    staged: Vec<String>,
    created: Option<PathBuf>,
    done: bool,
    fault: Fault,
    ops: usize,
}

impl OutputSet {
    /// Checks `dir` and opens a staging folder in it for tree `name`, whose report will be
    /// `report` (a file name inside `dir`). `inputs` are the run's input files: none of them may
    /// be the folder, and none will be replaced.
    pub fn prepare(dir: &Path, name: &str, report: &str, inputs: &[&Path]) -> Result<OutputSet> {
        check_output_folder(dir, inputs)?;
        let created = create_folder(dir)?;
        let set = OutputSet {
            dir: OutFolder::new(dir),
            name: name.to_string(),
            report: report.to_string(),
            staging: format!("{STAGING_PREFIX}{name}%{}", std::process::id()),
            staged: Vec::new(),
            created,
            done: false,
            fault: Fault::from_env(),
            ops: 0,
        };
        set.recover()?;
        set.dir
            .create_dir(&set.staging)
            .context("cannot write into the output folder")?;
        // Another run may have started between the look and the mkdir.
        if let Some(pid) = set.live_other_run()? {
            let _ = set.dir.remove_dir_all(&set.staging);
            bail!(
                "{}: another frond run (pid {pid}) is writing {name} into this folder",
                dir.display()
            );
        }
        Ok(set)
    }

    /// Refuses now, before any work, if a file the run will write is in the way (see the module
    /// doc); `names` are relative to the folder. [`OutputSet::commit`] checks every file again.
    pub fn check_names(&self, names: &[String]) -> Result<()> {
        let (owned, shared) = (self.owned_files()?, self.files_of_other_reports()?);
        for n in names {
            self.check_free(n, &owned, &shared)?;
        }
        Ok(())
    }

    /// Writes one file of the set (`rel`: a relative name, `shaders/x.wgsl` allowed) into the
    /// staging folder.
    pub fn stage(&mut self, rel: &str, bytes: &[u8]) -> Result<()> {
        let rel = checked_relative(rel)?;
        if self.staged.contains(&rel) {
            bail!("{rel}: written twice in one output set");
        }
        self.step()?;
        let staged = format!("{}/{rel}", self.staging);
        let shown = self.dir.root().join(&rel);
        let mut f = self
            .dir
            .create_file(&staged)
            .with_context(|| format!("{}: cannot write", shown.display()))?;
        f.write_all(bytes)
            .and_then(|()| f.sync_all())
            .with_context(|| format!("{}: cannot write", shown.display()))?;
        self.staged.push(rel);
        Ok(())
    }

    /// Where a staged file lies until the set is committed (to read back what was written).
    pub fn staged_path(&self, rel: &str) -> Option<PathBuf> {
        self.staged
            .iter()
            .any(|s| s == rel)
            .then(|| self.dir.root().join(&self.staging).join(rel))
    }

    /// Stages the report (`report_bytes`, the set's last file) and installs the whole set.
    pub fn commit(mut self, report_bytes: &[u8]) -> Result<()> {
        let report = self.report.clone();
        self.stage(&report, report_bytes)?;
        // Checked again: the folder may have changed during the build.
        let (owned, shared) = (self.owned_files()?, self.files_of_other_reports()?);
        for n in &self.staged {
            self.check_free(n, &owned, &shared)?;
        }
        let new: BTreeSet<&String> = self.staged.iter().collect();
        let mut remove: Vec<String> = Vec::new();
        // The old report goes first: from then on the folder says it is mid-install.
        if let Some(old) = &owned.report {
            remove.push(old.clone());
        }
        for f in &owned.files {
            if !new.contains(f) && !shared.contains(f) && !remove.contains(f) {
                remove.push(f.clone());
            }
        }
        // The report was staged last, so it is installed last.
        let journal = Journal {
            install: self.staged.clone(),
            remove,
        };
        self.step()?;
        let text = serde_json::to_vec_pretty(&journal).context("serialising the journal")?;
        let staging_path = self.dir.path(&self.staging)?;
        self.dir
            .write_atomic(format!("{}/{JOURNAL}", self.staging), &text)
            .and_then(|()| Ok(sync_dir(&staging_path)?))
            .with_context(|| format!("{}: cannot write the journal", staging_path.display()))?;
        // Committed: from here a failure is finished by the next run, not undone.
        self.done = true;
        let (dir, staging) = (self.dir.clone(), self.staging.clone());
        install(&dir, &staging, &journal, &mut || self.step())
    }

    /// Counts one file operation and applies `FROND_FAULT`.
    fn step(&mut self) -> Result<()> {
        self.ops += 1;
        match self.fault {
            Fault::AbortAfter(k) if self.ops > k => std::process::abort(),
            Fault::FailAfter(k) if self.ops > k => {
                bail!(
                    "{}: no space left on device (FROND_FAULT)",
                    self.dir.root().display()
                )
            }
            _ => Ok(()),
        }
    }

    /// Finishes or clears what killed runs of this tree left in the folder; refuses when a live
    /// run is staging it, and refuses (touching nothing) a journal that names anything outside
    /// the folder or a staging entry that is not a plain folder.
    fn recover(&self) -> Result<()> {
        if let Some(pid) = self.live_other_run()? {
            bail!(
                "{}: another frond run (pid {pid}) is writing {} into this folder",
                self.dir.root().display(),
                self.name
            );
        }
        let mut journals = Vec::new();
        let mut leftovers = Vec::new();
        for (staging, _) in self.stagings()? {
            if staging == self.staging {
                continue;
            }
            // An entry of the folder's own listing, looked at without following it.
            let path = self.dir.root().join(&staging);
            let is_dir = std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_dir());
            if !is_dir {
                bail!(
                    "{}: is not a staging folder frond made (a link or a file); nothing was \
                     changed: remove it if no frond run wrote it",
                    path.display()
                );
            }
            let journal = self.dir.path(format!("{staging}/{JOURNAL}"))?;
            if std::fs::symlink_metadata(&journal).is_ok() {
                let j = read_journal(&journal)?;
                check_journal(&self.dir, &staging, &j).with_context(|| {
                    format!(
                        "{}: refused: the journal of a killed run names a file outside the \
                         output folder; nothing was changed: remove {} if no frond run wrote it",
                        journal.display(),
                        path.display()
                    )
                })?;
                journals.push((staging, j));
            } else {
                leftovers.push(staging);
            }
        }
        // Every journal was checked before any is applied.
        for (staging, j) in journals {
            tracing::warn!(
                "{}: finishing the install of a run that was killed",
                self.dir.root().display()
            );
            install(&self.dir, &staging, &j, &mut || Ok(()))?;
        }
        for staging in leftovers {
            tracing::info!("{staging}: removing a killed run's staging");
            self.dir.remove_dir_all(&staging)?;
        }
        self.remove_stale_temp_files();
        Ok(())
    }

    /// `.<file>.tmp-<pid>` files of older frond versions' per-file writes, for this tree, whose
    /// process is gone.
    fn remove_stale_temp_files(&self) {
        let Ok(entries) = std::fs::read_dir(self.dir.root()) else {
            return;
        };
        let prefix = format!(".{}_", self.name);
        for e in entries.flatten() {
            let file = e.file_name().to_string_lossy().into_owned();
            let Some((stem, pid)) = file.rsplit_once(".tmp-") else {
                continue;
            };
            let ours = stem.starts_with(&prefix) || stem == ".report.json";
            if ours && pid.parse::<u32>().is_ok_and(|p| !process_alive(p)) {
                let _ = self.dir.remove_file(&file);
            }
        }
    }

    /// Names of this tree's staging folders in the folder, with their pid.
    fn stagings(&self) -> Result<Vec<(String, u32)>> {
        let prefix = format!("{STAGING_PREFIX}{}%", self.name);
        let mut out = Vec::new();
        let entries = std::fs::read_dir(self.dir.root())
            .with_context(|| format!("{}: cannot list", self.dir.root().display()))?;
        for e in entries.flatten() {
            let file = e.file_name().to_string_lossy().into_owned();
            if let Some(pid) = file.strip_prefix(&prefix).and_then(|p| p.parse().ok()) {
                out.push((file, pid));
            }
        }
        out.sort();
        Ok(out)
    }

    /// The pid of another live frond run staging this tree here.
    fn live_other_run(&self) -> Result<Option<u32>> {
        let me = std::process::id();
        Ok(self
            .stagings()?
            .into_iter()
            .map(|(_, pid)| pid)
            .find(|&pid| pid != me && process_alive(pid)))
    }

    /// This tree's previous set: its report and the files it lists.
    fn owned_files(&self) -> Result<Owned> {
        let current = self.dir.path(&self.report)?;
        if current.is_file() {
            return Ok(Owned {
                report: Some(self.report.clone()),
                files: listed_files(&current, self.dir.root())?,
            });
        }
        // frond before 0.2 wrote `report.json`; adopt its set when it is this tree's.
        let legacy = self.dir.path("report.json")?;
        if legacy.is_file()
            && let Ok(text) = std::fs::read(&legacy)
            && let Ok(listing) = serde_json::from_slice::<ReportListing>(&text)
            && listing.name.as_deref() == Some(self.name.as_str())
        {
            return Ok(Owned {
                report: Some("report.json".into()),
                files: listed_files(&legacy, self.dir.root())?,
            });
        }
        Ok(Owned::default())
    }

    /// Files listed by the reports of other trees in the folder (shared reference shaders).
    fn files_of_other_reports(&self) -> Result<BTreeSet<String>> {
        let mut out = BTreeSet::new();
        let entries = std::fs::read_dir(self.dir.root())
            .with_context(|| format!("{}: cannot list", self.dir.root().display()))?;
        for e in entries.flatten() {
            let file = e.file_name().to_string_lossy().into_owned();
            if file != self.report
                && (file.ends_with("_report.json") || file.ends_with("_cloud_stats.json"))
                && let Ok(path) = self.dir.path(&file)
            {
                out.extend(listed_files(&path, self.dir.root()).unwrap_or_default());
            }
        }
        Ok(out)
    }

    /// Refuses when `rel` exists in the folder and is not this tree's (`owned`), nor listed by
    /// another tree's report (`shared`).
    fn check_free(&self, rel: &str, owned: &Owned, shared: &BTreeSet<String>) -> Result<()> {
        let path = self.dir.path(rel)?;
        if std::fs::symlink_metadata(&path).is_err() {
            return Ok(());
        }
        let ours = owned.files.iter().any(|f| f == rel) || owned.report.as_deref() == Some(rel);
        if ours || shared.contains(rel) {
            if !std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file()) {
                bail!(
                    "{}: is in the way and is not a file frond wrote; move it or choose another output folder",
                    path.display()
                );
            }
            return Ok(());
        }
        bail!(
            "{}: already exists and no frond report of {} in this folder lists it; frond never \
             replaces a file it did not write (move it or choose another output folder)",
            path.display(),
            self.name
        )
    }
}

impl Drop for OutputSet {
    /// An uncommitted set (an error, a panic) leaves nothing: its staging folder goes, and the
    /// output folder too when this run created it and it is empty.
    fn drop(&mut self) {
        if self.done {
            return;
        }
        let _ = self.dir.remove_dir_all(&self.staging);
        if let Some(top) = &self.created {
            // Only empty folders: remove_dir refuses anything else.
            let mut d = Some(self.dir.root());
            while let Some(p) = d {
                if !OutFolder::new(p).remove_self_if_empty() || p == top {
                    break;
                }
                d = p.parent();
            }
        }
    }
}

/// A previous set of this tree.
#[derive(Default)]
struct Owned {
    report: Option<String>,
    files: Vec<String>,
}

/// Reads a killed run's journal.
fn read_journal(path: &Path) -> Result<Journal> {
    let text = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    serde_json::from_slice(&text)
        .with_context(|| format!("{}: not a frond journal", path.display()))
}

/// Every name the journal installs or removes is a plain name inside `dir` (and, installed,
/// inside the staging folder `staging`, a regular file while it is there), with no link out on
/// the way.
fn check_journal(dir: &OutFolder, staging: &str, journal: &Journal) -> Result<()> {
    for rel in journal.install.iter().chain(&journal.remove) {
        checked_relative(rel)?;
        dir.path(rel)?;
    }
    for rel in &journal.install {
        let staged = dir.path(format!("{staging}/{rel}"))?;
        // What is still staged is a file frond wrote, never a link (installed, a relative link
        // could point out of the folder).
        if std::fs::symlink_metadata(&staged).is_ok_and(|m| !m.is_file()) {
            bail!("{}: is not a file frond staged", staged.display());
        }
    }
    Ok(())
}

/// Installs a committed set (its journal checked by [`check_journal`]): removals, then renames
/// (the report last), then the journal and staging folder go. Idempotent, so a killed install
/// is finished by running it again.
fn install(
    dir: &OutFolder,
    staging: &str,
    journal: &Journal,
    step: &mut dyn FnMut() -> Result<()>,
) -> Result<()> {
    check_journal(dir, staging, journal)?;
    let staged = |rel: &str| format!("{staging}/{rel}");
    let exists = |rel: &str| {
        dir.path(rel)
            .is_ok_and(|p| std::fs::symlink_metadata(p).is_ok())
    };
    for rel in &journal.remove {
        // A name the new set also has is removed only while its new file is still staged:
        // once installed (a killed install being finished), it is the new file.
        let replaced_already = journal.install.contains(rel) && !exists(&staged(rel));
        if !replaced_already && exists(rel) {
            step()?;
            dir.remove_file(rel).context("removing the old file")?;
        }
        if let Some(parent) = Path::new(rel).parent()
            && !parent.as_os_str().is_empty()
        {
            // An emptied subfolder of the old set (shaders/) goes too; a non-empty one stays.
            let _ = dir.remove_dir(parent);
        }
    }
    for rel in &journal.install {
        if !exists(&staged(rel)) {
            // Installed before a kill.
            continue;
        }
        step()?;
        if let Some(parent) = Path::new(rel).parent()
            && !parent.as_os_str().is_empty()
        {
            dir.create_dir_all(parent)?;
        }
        dir.rename(staged(rel), rel)?;
    }
    sync_dir(dir.root()).with_context(|| format!("{}: cannot sync", dir.root().display()))?;
    dir.remove_dir_all(staging)?;
    Ok(())
}

/// The files a report lists (`files`), as names relative to `dir`.
fn listed_files(report: &Path, dir: &Path) -> Result<Vec<String>> {
    let text =
        std::fs::read(report).with_context(|| format!("{}: cannot read", report.display()))?;
    let listing: ReportListing = serde_json::from_slice(&text)
        .with_context(|| format!("{}: not a JSON report", report.display()))?;
    Ok(listing
        .files
        .iter()
        .filter_map(|f| relative_name(f, dir))
        .collect())
}

/// What an output set reads back of a report (`<name>_report.json`, or an older
/// `report.json`): whose set it is and the files it lists. Typed, and only these two fields, so
/// that any frond version's report is read.
#[derive(serde::Deserialize)]
struct ReportListing {
    /// The tree's name.
    #[serde(default)]
    name: Option<String>,
    /// Every file of the set, relative to the folder (or, before frond 0.2, to `-o`).
    #[serde(default)]
    files: Vec<String>,
}

/// One `files` entry as a plain name relative to `dir`. frond 0.2 lists names relative to the
/// folder; 0.1 listed `<-o as spelt>/<file>` (`out/x.glb`, `/abs/out/x.glb`). Of the entry
/// itself, its part below `dir` and its file name, the first that names a file in the folder
/// wins, else the file name. A name through a link out of the folder is never one.
fn relative_name(entry: &str, dir: &Path) -> Option<String> {
    let p = Path::new(entry);
    let names: Vec<&str> = [
        Some(p),
        p.strip_prefix(dir).ok(),
        p.file_name().map(Path::new),
    ]
    .into_iter()
    .flatten()
    .filter_map(Path::to_str)
    .filter(|n| checked_relative(n).is_ok() && checked_path(dir, n).is_ok())
    .collect();
    names
        .iter()
        .find(|n| dir.join(n).exists())
        .or(names.last())
        .map(|n| n.to_string())
}

/// A relative name without `..`, root or prefix.
fn checked_relative(rel: &str) -> Result<String> {
    let p = Path::new(rel);
    if rel.is_empty() || !p.components().all(|c| matches!(c, Component::Normal(_))) {
        bail!("'{rel}' is not a plain relative file name");
    }
    Ok(rel.to_string())
}

/// Refuses an output folder that is a system root, an existing non-folder, or an input file.
pub fn check_output_folder(dir: &Path, inputs: &[&Path]) -> Result<()> {
    let canon = dir.canonicalize().ok();
    let shown = canon.as_deref().unwrap_or(dir);
    if let Some(c) = &canon
        && SYSTEM_ROOTS.iter().any(|r| c == Path::new(r))
    {
        bail!(
            "{}: refusing to write into a system folder; give a folder of your own with -o",
            shown.display()
        );
    }
    for input in inputs {
        if let (Some(c), Ok(i)) = (&canon, input.canonicalize())
            && *c == i
        {
            bail!(
                "{}: -o names the input file; give a folder for the output",
                dir.display()
            );
        }
    }
    if let Ok(meta) = std::fs::metadata(dir)
        && !meta.is_dir()
    {
        bail!("{}: -o exists and is not a folder", dir.display());
    }
    Ok(())
}

/// Creates `dir` (and missing parents); returns the topmost folder created, if any.
fn create_folder(dir: &Path) -> Result<Option<PathBuf>> {
    let mut top = None;
    let mut p = Some(dir);
    while let Some(d) = p {
        if d.as_os_str().is_empty() || d.exists() {
            break;
        }
        top = Some(d.to_path_buf());
        p = d.parent();
    }
    OutFolder::new(dir)
        .create()
        .context("cannot create the output folder")?;
    Ok(top)
}

/// Whether process `pid` is a live frond (signal 0 reaches it, and where `/proc` tells, its
/// command name says frond: a pid reused by another program does not hold a folder forever).
fn process_alive(pid: u32) -> bool {
    let Ok(raw) = i32::try_from(pid) else {
        return false;
    };
    // SAFETY: kill with signal 0 sends nothing; it only checks that the process exists.
    let r = unsafe { libc::kill(raw, 0) };
    let exists = r == 0 || std::io::Error::last_os_error().raw_os_error() == Some(libc::EPERM);
    exists
        && std::fs::read_to_string(format!("/proc/{pid}/comm"))
            .map(|c| c.contains("frond"))
            .unwrap_or(true)
}

/// fsync of a folder, so renames in it survive a power cut.
fn sync_dir(dir: &Path) -> std::io::Result<()> {
    std::fs::File::open(dir)?.sync_all()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn report_entries_of_both_versions_name_files_in_the_folder() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir_all(d.join("shaders")).unwrap();
        std::fs::write(d.join("oak_LOD0.glb"), b"x").unwrap();
        std::fs::write(d.join("shaders/frond_vat.wgsl"), b"x").unwrap();
        let name = |e: &str| relative_name(e, d);
        // 0.2: relative to the folder.
        assert_eq!(name("oak_LOD0.glb").as_deref(), Some("oak_LOD0.glb"));
        assert_eq!(
            name("shaders/frond_vat.wgsl").as_deref(),
            Some("shaders/frond_vat.wgsl")
        );
        // 0.1: `-o out` spelt relative, or absolute.
        assert_eq!(name("out/oak_LOD0.glb").as_deref(), Some("oak_LOD0.glb"));
        let abs = d.join("shaders/frond_vat.wgsl");
        assert_eq!(
            name(abs.to_str().unwrap()).as_deref(),
            Some("shaders/frond_vat.wgsl")
        );
        // Never a name outside the folder.
        assert_eq!(name("../oak_LOD0.glb").as_deref(), Some("oak_LOD0.glb"));
        assert_eq!(name("..").as_deref(), None);
    }
}
