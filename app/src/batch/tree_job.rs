//! One tree of a batch: skip it when its output is up to date, else run `frond lod` (and
//! `frond eval`) as child processes into a private folder and rename that into place, so a
//! kill at any moment leaves either the old complete output, none, or the new complete one.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::{Context, Result};
use sha2::{Digest, Sha256};

use frond_lod::{LodReport, ReportTimings};
use frond_metrics::EvalReport;
use frond_scene::InputLimits;

use super::inputs::{Overrides, TreeInput, hex, input_hash};
use super::summary::{FileEntry, LodLine, LodMetric, Status, TreeEntry};
use crate::child_job::{ChildSpec, JobEnd, run_child};
use crate::child_request::ChildRequest;
use crate::engine_preset::EnginePreset;
use crate::eval_cmd::EvalSettings;
use crate::lod_settings::{
    Animation, BuildSettings, Engine, LodSettings, MethodChoice, Named, ReadSettings,
};
use crate::out_folder::OutFolder;
use frond_preview::VIEWER_DIR;

/// Name of each tree's stamp, written last into its output folder.
pub const STAMP: &str = "batch.json";
/// `frond lod`'s report of the tree read from `input` (`<name>_report.json`).
pub fn report_file(input: &Path) -> String {
    frond_lod::report::report_name(&crate::lod_cmd::name_of(input))
}
/// Private folder under OUTDIR for outputs being written.
pub const TMP_DIR: &str = ".frond-tmp";
/// Folder under OUTDIR with each tree's last `frond lod`/`frond eval` logs.
pub const LOG_DIR: &str = ".frond-logs";

/// What every tree of a batch shares.
#[derive(Clone, Debug)]
pub struct TreeContext {
    /// The `frond` executable the children run.
    pub exe: PathBuf,
    /// OUTDIR, absolute.
    pub out_dir: PathBuf,
    /// Settings from the command line (a manifest's override them).
    pub defaults: Overrides,
    /// Plane search and bake options passed to every `frond lod` (clouds and clusters come
    /// from each tree's settings).
    pub build: BuildSettings,
    /// The engine preset every tree is built for, and whose limits each GLB is checked
    /// against.
    pub preset: Option<EnginePreset>,
    /// Run `frond eval` on each LOD and put its metrics' means in the LOD's summary line.
    pub eval: bool,
    /// Each tree's `frond lod` writes its preview page (`frond batch --no-preview` skips it).
    pub preview: bool,
    /// How long one child (a tree's `frond lod`, or one LOD's `frond eval`) may run before
    /// it is killed and the tree recorded as failed.
    pub timeout: Duration,
    /// `RAYON_NUM_THREADS` of each child.
    pub threads: usize,
    /// What reading an input may cost: used to hash the inputs, and passed to every child.
    pub limits: InputLimits,
}

/// The `frond lod` settings of a tree with `o` as its settings (input and output set when it
/// runs): `frond lod`'s defaults with the settings, the batch's build options and the engine
/// preset applied.
pub fn lod_settings(ctx: &TreeContext, o: &Overrides, output: &str) -> Result<LodSettings> {
    let mut l = LodSettings::defaults(Path::new("tree.glb"), Path::new("."));
    // The batch measures with its own `eval` children when asked (`--eval`): the full report,
    // not the error alone.
    l.measure = false;
    l.preview = ctx.preview;
    // One copy of the preview's viewer scripts for the whole batch, in OUTDIR/viewer.
    let depth = Path::new(output).components().count();
    l.preview_viewer = Some(format!("{}{VIEWER_DIR}", "../".repeat(depth)));
    if let Some(m) = &o.method {
        l.method = MethodChoice::parse(m).with_context(|| format!("unknown method '{m}'"))?;
    }
    if let Some(h) = &o.lods {
        l.lods = h.clone();
    }
    if let Some(a) = &o.animation {
        l.animation = Animation::parse(a)
            .with_context(|| format!("unknown animation '{a}' (one of {})", Animation::list()))?;
    }
    if let Some(s) = o.seed {
        l.sampling.seed = s;
    }
    if let Some(p) = o.pixel_error {
        l.pixel_error = p;
    }
    if let Some(s) = o.samples {
        l.sampling.samples = s;
    }
    l.sampling.clip = o.clip.clone();
    l.read = reading(ctx, o);
    l.build = BuildSettings {
        clouds: o.clouds,
        clusters: o.clusters,
        ..ctx.build.clone()
    };
    l.preset = ctx.preset.and_then(|p| Engine::parse(p.name));
    crate::engine_preset::with_preset(l)
}

/// How a tree is read: its foliage and wood materials, the batch's input limits.
fn reading(ctx: &TreeContext, o: &Overrides) -> ReadSettings {
    ReadSettings {
        foliage_materials: o.foliage_material.clone().unwrap_or_default(),
        wood_materials: o.wood_material.clone().unwrap_or_default(),
        limits: ctx.limits,
    }
}

/// The hash of what decides a tree's output besides its input.
pub fn params_hash(settings: &LodSettings, eval: bool) -> String {
    let key = serde_json::json!({
        "frond": env!("CARGO_PKG_VERSION"),
        "settings": settings,
        "eval": eval,
    });
    hex(&Sha256::digest(key.to_string().as_bytes()))
}

/// A file-name-safe key of an output folder (`/` and `%` escaped); its temporary folders are
/// `<key>%<pid>` and `<key>%old%<pid>`.
fn tmp_key(output: &str) -> String {
    output.replace('%', "%25").replace('/', "%2F")
}

/// Processes one tree; never fails: a failure is the entry's status and reason.
pub fn process(ctx: &TreeContext, tree: &TreeInput) -> TreeEntry {
    let overrides = tree.overrides.or(&ctx.defaults);
    let settings = lod_settings(ctx, &overrides, &tree.output);
    let mut entry = TreeEntry {
        reason: None,
        settings: settings.as_ref().ok().cloned(),
        preset: ctx.preset.map(|p| p.name.to_string()),
        ..TreeEntry::failed(tree, "")
    };
    entry.params_hash = settings
        .as_ref()
        .map(|s| params_hash(s, ctx.eval))
        .unwrap_or_default();
    let start = Instant::now();
    let result = settings.and_then(|s| build(ctx, tree, &overrides, s, &mut entry));
    entry.wall_s = start.elapsed().as_secs_f64();
    match result {
        Ok(status) => entry.status = status,
        Err(e) => {
            // The tree is named by the error line already: drop its absolute path.
            let mut reason = format!("{e:#}");
            if let Ok(abs) = std::path::absolute(&tree.path) {
                reason = reason.replace(&format!("{}: ", abs.display()), "");
            }
            entry.status = Status::Failed;
            entry.reason = Some(reason);
            entry.files.clear();
            entry.lods.clear();
            entry.output_bytes = 0;
        }
    }
    entry
}

/// The stamp of a complete earlier output with the same input and parameters.
fn up_to_date(dir: &Path, report: &str, input_hash: &str, params_hash: &str) -> Option<TreeEntry> {
    let stamp: TreeEntry = serde_json::from_slice(&std::fs::read(dir.join(STAMP)).ok()?).ok()?;
    let same = stamp.input_hash.as_deref() == Some(input_hash) && stamp.params_hash == params_hash;
    let complete = dir.join(report).is_file()
        && stamp.files.iter().all(|f| {
            std::fs::metadata(dir.join(&f.name)).is_ok_and(|m| m.is_file() && m.len() == f.bytes)
        });
    (same && complete).then_some(stamp)
}

fn build(
    ctx: &TreeContext,
    tree: &TreeInput,
    overrides: &Overrides,
    settings: LodSettings,
    entry: &mut TreeEntry,
) -> Result<Status> {
    let hash = input_hash(&tree.path, &ctx.limits)?;
    entry.input_hash = Some(hash.clone());
    let out = OutFolder::new(&ctx.out_dir);
    let final_dir = out.path(&tree.output)?;
    let key = tmp_key(&tree.output);
    let tmp_root = out.sub(TMP_DIR)?;
    clear_leftovers(&tmp_root, &key);
    let report = report_file(&tree.path);
    if let Some(stamp) = up_to_date(&final_dir, &report, &hash, &entry.params_hash) {
        // Named as the tree is now (a manifest may have moved its input).
        *entry = TreeEntry {
            status: Status::UpToDate,
            tree: tree.relative.clone(),
            output: tree.output.clone(),
            ..stamp
        };
        return Ok(Status::UpToDate);
    }

    let tmp_name = format!("{key}%{}", std::process::id());
    let tmp = tmp_root.create_dir_all(&tmp_name)?;
    let result = build_into(ctx, tree, overrides, settings, entry, &tmp, &key)
        .and_then(|()| swap_into_place(&out, &tmp_name, &tree.output, &key));
    if result.is_err() {
        let _ = tmp_root.remove_dir_all(&tmp_name);
    }
    result.map(|()| Status::Built)
}

/// Removes this tree's folders a killed run left in `tmp_root`: exactly `<key>%<pid>` and
/// `<key>%old%<pid>` (only this tree's process writes them; other trees' keys may share the
/// prefix, never the whole name).
fn clear_leftovers(tmp_root: &OutFolder, key: &str) {
    let Ok(list) = std::fs::read_dir(tmp_root.root()) else {
        return;
    };
    let digits = |t: &str| !t.is_empty() && t.bytes().all(|b| b.is_ascii_digit());
    for e in list.flatten() {
        let name = e.file_name().to_string_lossy().into_owned();
        let mine = name
            .strip_prefix(key)
            .and_then(|r| r.strip_prefix('%'))
            .is_some_and(|r| digits(r) || r.strip_prefix("old%").is_some_and(digits));
        if mine {
            let _ = tmp_root.remove_dir_all(&name);
        }
    }
}

/// Runs the children into `tmp` and fills `entry`; writes the stamp last.
fn build_into(
    ctx: &TreeContext,
    tree: &TreeInput,
    overrides: &Overrides,
    settings: LodSettings,
    entry: &mut TreeEntry,
    tmp: &Path,
    key: &str,
) -> Result<()> {
    let input = std::path::absolute(&tree.path)
        .with_context(|| format!("{}: cannot resolve", tree.path.display()))?;
    let log_dir = OutFolder::new(&ctx.out_dir).path(format!("{LOG_DIR}/{key}"))?;
    let spec = ChildSpec {
        cwd: Some(tmp),
        env: vec![("RAYON_NUM_THREADS".into(), ctx.threads.max(1).to_string())],
    };
    let lod = ChildRequest::Lod(LodSettings {
        input: input.clone(),
        output: ".".into(),
        ..settings
    });
    let run = run_child(&ctx.exe, &lod, &spec, &log_dir, "lod", ctx.timeout)?;
    entry.peak_rss_bytes = run.peak_rss;
    check_end(run.end, "lod")?;

    let report_name = report_file(&tree.path);
    let report_path = tmp.join(&report_name);
    let report: LodReport = serde_json::from_slice(
        &std::fs::read(&report_path)
            .with_context(|| format!("{}: frond lod wrote no report", report_path.display()))?,
    )
    .with_context(|| format!("frond lod's {report_name} is not a frond lod report"))?;
    entry.times_s.extend(stage_times(&report.timings_s));
    for l in &report.lods {
        entry.lods.push(LodLine {
            file: l.file.clone(),
            screen_height: l.screen_height,
            method: l.method.name().to_string(),
            triangles: l.triangles as u64,
            billboards: l.billboards as u64,
            bones: l.bones as u64,
            texture_bytes: l.texture_bytes as u64,
            metrics: BTreeMap::new(),
        });
    }

    if ctx.eval {
        let t0 = Instant::now();
        for (k, l) in entry.lods.iter_mut().enumerate() {
            let Some(h) = l.screen_height else { continue };
            let tag = format!("eval{k}");
            let eval = ChildRequest::Eval(EvalSettings {
                read: reading(ctx, overrides),
                screen_height: h,
                samples: overrides.samples.unwrap_or(64),
                clip: overrides.clip.clone(),
                ..EvalSettings::defaults(&input, Path::new(&l.file))
            });
            let run = run_child(&ctx.exe, &eval, &spec, &log_dir, &tag, ctx.timeout)?;
            if let Some(p) = run.peak_rss {
                entry.peak_rss_bytes = Some(entry.peak_rss_bytes.map_or(p, |q| q.max(p)));
            }
            check_end(run.end, &format!("eval of {}", l.file))?;
            let out = log_dir.join(format!("{tag}.stdout"));
            let r: EvalReport = serde_json::from_slice(
                &std::fs::read(&out).with_context(|| format!("{}: cannot read", out.display()))?,
            )
            .with_context(|| format!("frond eval of {} printed no report", l.file))?;
            for m in LodMetric::ALL {
                l.metrics.insert(m, m.of(&r));
            }
        }
        entry
            .times_s
            .insert("eval".into(), t0.elapsed().as_secs_f64());
    }

    // The report's size follows its timing fields: listed apart, checked for presence.
    entry.files = list_files(tmp)?
        .into_iter()
        .filter(|f| f.name != report_name)
        .collect();
    entry.output_bytes = entry.files.iter().map(|f| f.bytes).sum();
    if let Some(p) = &ctx.preset {
        // Every GLB written (each LOD and the combined file), as the engine will read it.
        for f in entry.files.iter().filter(|f| f.name.ends_with(".glb")) {
            let bytes = std::fs::read(tmp.join(&f.name))
                .with_context(|| format!("{}: cannot read", f.name))?;
            let glb = gltf::binary::Glb::from_slice(&bytes)
                .map_err(|e| anyhow::anyhow!("{}: not a GLB ({e})", f.name))?;
            let doc = gltf::json::Root::from_slice(&glb.json)
                .map_err(|e| anyhow::anyhow!("{}: not glTF JSON ({e})", f.name))?;
            entry.warnings.extend(p.check_file(&f.name, &doc));
        }
    }
    let stamp = TreeEntry {
        status: Status::Built,
        ..entry.clone()
    };
    OutFolder::new(tmp).write_atomic(
        STAMP,
        &serde_json::to_vec_pretty(&stamp).context("serialising the stamp")?,
    )
}

/// The run's stage times by name, the stages that ran.
fn stage_times(t: &ReportTimings) -> Vec<(String, f64)> {
    [
        ("build", Some(t.build)),
        ("export", Some(t.export)),
        ("measure", t.measure),
        ("measure_input", t.measure_input),
        ("preview", t.preview),
        ("sample", Some(t.sample)),
        ("total", Some(t.total)),
        ("wall", Some(t.wall)),
    ]
    .into_iter()
    .filter_map(|(k, v)| Some((k.to_string(), v?)))
    .collect()
}

fn check_end(end: JobEnd, what: &str) -> Result<()> {
    match end {
        JobEnd::Done => Ok(()),
        JobEnd::TimedOut(d) => anyhow::bail!("{what} ran past its time limit of {} s", d.as_secs()),
        JobEnd::Failed(why) => {
            // "exit 1: error: FILE: problem" → "FILE: problem".
            let why = why
                .split_once(": error: ")
                .map_or(why.as_str(), |(_, rest)| rest);
            anyhow::bail!("{why}")
        }
    }
}

/// Every file below `dir`, `/`-separated, sorted.
fn list_files(dir: &Path) -> Result<Vec<FileEntry>> {
    fn walk(root: &Path, dir: &Path, out: &mut Vec<FileEntry>) -> Result<()> {
        for e in
            std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?
        {
            let e = e.with_context(|| format!("{}: cannot list", dir.display()))?;
            let path = e.path();
            let meta = e
                .metadata()
                .with_context(|| format!("{}: cannot stat", path.display()))?;
            if meta.is_dir() {
                walk(root, &path, out)?;
            } else if let Ok(rel) = path.strip_prefix(root) {
                let name = rel
                    .components()
                    .map(|c| c.as_os_str().to_string_lossy().into_owned())
                    .collect::<Vec<_>>()
                    .join("/");
                out.push(FileEntry {
                    name,
                    bytes: meta.len(),
                });
            }
        }
        Ok(())
    }
    let mut out = Vec::new();
    walk(dir, dir, &mut out)?;
    out.sort_by(|a, b| a.name.cmp(&b.name));
    Ok(out)
}

/// Replaces the tree's output folder `output` in `out` by the complete `TMP_DIR/tmp`: the old
/// output is moved aside first, so at any moment the path holds a complete output or nothing.
fn swap_into_place(out: &OutFolder, tmp: &str, output: &str, key: &str) -> Result<()> {
    let final_dir = out.path(output)?;
    if let Some(parent) = Path::new(output).parent()
        && !parent.as_os_str().is_empty()
    {
        out.create_dir_all(parent)?;
    }
    // Only ever replace what a batch wrote: a folder with a stamp (or an empty one).
    let meta = std::fs::symlink_metadata(&final_dir);
    if meta.as_ref().is_ok_and(|m| !m.is_dir()) {
        anyhow::bail!(
            "{} exists and is not a folder; move it away or choose another output folder",
            final_dir.display()
        );
    }
    if meta.is_ok()
        && !out.path(format!("{output}/{STAMP}"))?.is_file()
        && std::fs::read_dir(&final_dir).is_ok_and(|mut d| d.next().is_some())
    {
        anyhow::bail!(
            "{} exists and is not a frond batch output (no {STAMP}); move it away or choose \
             another output folder",
            final_dir.display()
        );
    }
    let old = format!("{TMP_DIR}/{key}%old%{}", std::process::id());
    let had_old = meta.is_ok();
    if had_old {
        out.rename(output, &old)
            .context("cannot move the old output aside")?;
    }
    out.rename(format!("{TMP_DIR}/{tmp}"), output)
        .context("cannot move the output into place")?;
    if had_old {
        let _ = out.remove_dir_all(&old);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn leftovers_are_cleared_by_exact_name_only() {
        let dir = tempfile::tempdir().unwrap();
        let key = tmp_key("a");
        assert_eq!(tmp_key("a/b%c"), "a%2Fb%25c");
        for name in [
            "a%12",
            "a%old%12",
            "a%2Fb%12",
            "a%25x%12",
            "a%2Fb%old%3",
            "ab%12",
        ] {
            std::fs::create_dir_all(dir.path().join(name)).unwrap();
        }
        clear_leftovers(&OutFolder::new(dir.path()), &key);
        let mut left: Vec<String> = std::fs::read_dir(dir.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        left.sort();
        assert_eq!(left, ["a%25x%12", "a%2Fb%12", "a%2Fb%old%3", "ab%12"]);
    }
}
