//! `summary.json` and `summary.csv` of a batch (one line a tree), the stamp each finished tree
//! keeps beside its files, and the merge of shard summaries.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use frond_metrics::{EvalReport, MetricId};
use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::shard::Shard;
use crate::csv_text::text_cell;
use crate::out_folder::write_atomic;

/// What happened to a tree.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Status {
    /// Built by this run.
    Built,
    /// Its output matched the input hash and parameters already; left as it was.
    UpToDate,
    /// Not built: the reason is in [`TreeEntry::reason`]; an older output, if any, is kept.
    Failed,
}

/// One output file and its size.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FileEntry {
    /// File name, relative to the tree's output folder.
    pub name: String,
    /// Size in bytes.
    pub bytes: u64,
}

/// A number of `frond eval` that a LOD's summary line keeps with `--eval` (docs/batch.md),
/// measured at the LOD's own screen height: a metric's mean, or the coverage ratio. Written as
/// its key ([`LodMetric::key`]), in declaration order.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum LodMetric {
    /// [`MetricId::CoverageStatic`]: the coverage error on the loop's first frame.
    CoverageStatic,
    /// [`MetricId::CoverageAnimated`]: the LOD's coverage error over the loop (spec §5.4 on
    /// covered fractions), as `frond lod` reports it.
    CoverageAnimated,
    /// The coverage ratio ([`frond_metrics::CoverageMetrics::ratio`]): the LOD's covered area
    /// over the input's, per (view, frame) and then the mean; below 1 the LOD thins, above 1
    /// it bloats.
    CoverageRatio,
    /// [`MetricId::CoverageBinary`]: the thesis' binary coverage error.
    CoverageBinary,
    /// [`MetricId::CoverageFoliage`]: the coverage error of the foliage alone.
    CoverageFoliage,
    /// [`MetricId::ColourDifference`].
    ColourDifference,
    /// [`MetricId::ProjectedDistance`].
    ProjectedDistance,
    /// [`MetricId::Orientation`].
    Orientation,
    /// [`MetricId::DominatingAxis`].
    DominatingAxis,
}

impl LodMetric {
    /// Every number the summary keeps per LOD, in order.
    pub const ALL: [LodMetric; 9] = [
        LodMetric::CoverageStatic,
        LodMetric::CoverageAnimated,
        LodMetric::CoverageRatio,
        LodMetric::CoverageBinary,
        LodMetric::CoverageFoliage,
        LodMetric::ColourDifference,
        LodMetric::ProjectedDistance,
        LodMetric::Orientation,
        LodMetric::DominatingAxis,
    ];

    /// The eval metric whose mean it is; None for the coverage ratio.
    pub fn metric_id(self) -> Option<MetricId> {
        match self {
            LodMetric::CoverageStatic => Some(MetricId::CoverageStatic),
            LodMetric::CoverageAnimated => Some(MetricId::CoverageAnimated),
            LodMetric::CoverageRatio => None,
            LodMetric::CoverageBinary => Some(MetricId::CoverageBinary),
            LodMetric::CoverageFoliage => Some(MetricId::CoverageFoliage),
            LodMetric::ColourDifference => Some(MetricId::ColourDifference),
            LodMetric::ProjectedDistance => Some(MetricId::ProjectedDistance),
            LodMetric::Orientation => Some(MetricId::Orientation),
            LodMetric::DominatingAxis => Some(MetricId::DominatingAxis),
        }
    }

    /// Its key in `summary.json`'s `metrics` and its `summary.csv` column: the metric's
    /// `results.csv` column ([`MetricId::column`]), or `coverage_ratio`.
    pub fn key(self) -> &'static str {
        self.metric_id().map_or("coverage_ratio", MetricId::column)
    }

    /// The one whose key is `key`.
    pub fn from_key(key: &str) -> Option<LodMetric> {
        LodMetric::ALL.into_iter().find(|m| m.key() == key)
    }

    /// Its value in `report`: the metric's mean (None when skipped), or the ratio (None when
    /// not a number).
    pub fn of(self, report: &EvalReport) -> Option<f64> {
        match self.metric_id() {
            Some(id) => report.metric(id).mean,
            None => Some(report.coverage.ratio).filter(|r| r.is_finite()),
        }
    }
}

impl Serialize for LodMetric {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.key())
    }
}

impl<'de> Deserialize<'de> for LodMetric {
    /// A key of [`LodMetric::ALL`]; any other (a summary written before the coverage metric
    /// measured covered fractions called the static error `coverage`) is an error, so an
    /// older tree's stamp does not pass for up to date.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<LodMetric, D::Error> {
        let key = String::deserialize(d)?;
        LodMetric::from_key(&key)
            .ok_or_else(|| D::Error::custom(format!("'{key}' is not a summary metric")))
    }
}

/// One LOD of a tree, from its `report.json` (and `frond eval` with `--eval`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LodLine {
    /// The LOD's GLB, relative to the tree's output folder.
    pub file: String,
    /// Pixels the tree covers when this LOD is shown (None for LOD0, the input itself).
    pub screen_height: Option<f32>,
    /// The method the LOD was built with (`auto` resolved).
    pub method: String,
    /// Triangles drawn: the wood plus two per billboard.
    pub triangles: u64,
    /// Billboards (textured quads) of the LOD.
    pub billboards: u64,
    /// Joints of the LOD's skin.
    pub bones: u64,
    /// Decoded bytes (RGBA8) of every image the LOD draws with.
    pub texture_bytes: u64,
    /// `frond eval`'s numbers at the LOD's screen height ([`LodMetric`]; with `--eval`, not
    /// for LOD0, the input itself); None where the metric was skipped.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub metrics: BTreeMap<LodMetric, Option<f64>>,
}

impl LodLine {
    /// The LOD's `metric`, when it was measured and has a value.
    pub fn metric(&self, metric: LodMetric) -> Option<f64> {
        self.metrics.get(&metric).copied().flatten()
    }
}

/// One tree's line of the summary; also its stamp `batch.json` in its output folder.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TreeEntry {
    /// Path relative to INPUT.
    pub tree: String,
    /// Output folder relative to OUTDIR.
    pub output: String,
    /// Built, up to date or failed.
    pub status: Status,
    /// Why it failed.
    pub reason: Option<String>,
    /// SHA-256 of the input file(s).
    pub input_hash: Option<String>,
    /// SHA-256 of `frond`'s version, the settings and `--eval`.
    pub params_hash: String,
    /// The `frond lod` settings the tree was built with (None when they could not be made).
    pub settings: Option<crate::lod_settings::LodSettings>,
    /// The engine preset's name the tree was built for (None: no preset).
    pub preset: Option<String>,
    /// The files written (`report.json`, whose size follows its timing fields, aside).
    pub files: Vec<FileEntry>,
    /// Bytes of the files in `files` together.
    pub output_bytes: u64,
    /// Each LOD's line, LOD0 (the input) first.
    pub lods: Vec<LodLine>,
    /// The engine preset's limits a written GLB breaks.
    pub warnings: Vec<String>,
    /// Timing: `frond lod`'s stage times (sample, build, export, total) and eval's.
    pub times_s: BTreeMap<String, f64>,
    /// Timing: wall time of the tree's processes, and their peak resident memory.
    pub wall_s: f64,
    /// Largest resident memory of any of its processes, bytes (None where not measured).
    pub peak_rss_bytes: Option<u64>,
}

impl TreeEntry {
    /// A tree that failed before anything about it was known.
    pub fn failed(tree: &super::inputs::TreeInput, reason: &str) -> TreeEntry {
        TreeEntry {
            tree: tree.relative.clone(),
            output: tree.output.clone(),
            status: Status::Failed,
            reason: Some(reason.to_string()),
            input_hash: None,
            params_hash: String::new(),
            settings: None,
            preset: None,
            files: Vec::new(),
            output_bytes: 0,
            lods: Vec::new(),
            warnings: Vec::new(),
            times_s: BTreeMap::new(),
            wall_s: 0.0,
            peak_rss_bytes: None,
        }
    }

    /// The entry without its timing fields (what equal runs share).
    pub fn without_timing(&self) -> TreeEntry {
        TreeEntry {
            times_s: BTreeMap::new(),
            wall_s: 0.0,
            peak_rss_bytes: None,
            ..self.clone()
        }
    }
}

/// Trees by status.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Counts {
    /// Trees in the summary.
    pub trees: usize,
    /// Trees built by the run.
    pub built: usize,
    /// Trees skipped because their output was already up to date.
    pub up_to_date: usize,
    /// Trees that failed.
    pub failed: usize,
}

impl Counts {
    /// Counts the entries by their status.
    pub fn of(trees: &[TreeEntry]) -> Counts {
        let n = |s| trees.iter().filter(|t| t.status == s).count();
        Counts {
            trees: trees.len(),
            built: n(Status::Built),
            up_to_date: n(Status::UpToDate),
            failed: n(Status::Failed),
        }
    }

    /// The batch's last line.
    pub fn line(&self) -> String {
        format!(
            "{} trees: {} built, {} up to date, {} failed",
            self.trees, self.built, self.up_to_date, self.failed
        )
    }
}

/// `summary.json`.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BatchSummary {
    /// Version of the `frond` that ran the batch.
    pub frond: String,
    /// INPUT as given: the library folder or the manifest.
    pub input: String,
    /// The engine preset's name (None: no preset).
    pub preset: Option<String>,
    /// The shard this run did (None: every tree).
    pub shard: Option<Shard>,
    /// Summaries `frond batch-merge` read.
    #[serde(default)]
    pub merged_from: Vec<String>,
    /// Trees by status.
    pub counts: Counts,
    /// Sorted by `tree`.
    pub trees: Vec<TreeEntry>,
    /// Timing: the run's wall time and most trees at once.
    pub wall_s: f64,
    /// Workers the run used: the trees-at-once limit it was given
    /// ([`BatchRequest::jobs`](super::BatchRequest::jobs)), at most one per tree.
    pub jobs: usize,
}

impl BatchSummary {
    /// File stem: `summary`, or `summary.shard-0001-of-0004` for a shard.
    pub fn stem(shard: Option<Shard>) -> String {
        match shard {
            Some(s) => format!("summary.{}", s.tag()),
            None => "summary".into(),
        }
    }

    /// Writes `<stem>.json` and `<stem>.csv` into `dir`, atomically.
    pub fn write(&self, dir: &Path, stem: &str) -> Result<()> {
        let json = serde_json::to_vec_pretty(self).context("serialising the summary")?;
        write_atomic(&dir.join(format!("{stem}.csv")), &self.csv()?)?;
        if stem == "summary" {
            write_atomic(&dir.join("index.html"), self.index_page().as_bytes())?;
        }
        write_atomic(&dir.join(format!("{stem}.json")), &json)
    }

    /// `index.html`: one line per tree linking its preview page (when it wrote one), with its
    /// LOD0 still, what was made, or why it failed; `frond view OUTDIR` opens it.
    pub fn index_page(&self) -> String {
        use frond_preview::index_page::{IndexEntry, index_page, trees_line};
        let entries: Vec<IndexEntry> = self
            .trees
            .iter()
            .map(|t| {
                let page = t
                    .files
                    .iter()
                    .find(|f| f.name.ends_with("_preview.html"))
                    .map(|f| format!("{}/{}", t.output, f.name));
                let thumbnail = page
                    .as_ref()
                    .map(|p| format!("{}/lod0.png", p.trim_end_matches(".html")));
                let summary = match (&t.status, &t.reason) {
                    (Status::Failed, reason) => {
                        format!("failed: {}", reason.as_deref().unwrap_or("unknown"))
                    }
                    _ => format!(
                        "{} LODs, {} → {} triangles, {} written{}",
                        t.lods.len().saturating_sub(1),
                        t.lods.first().map_or(0, |l| l.triangles),
                        t.lods.last().map_or(0, |l| l.triangles),
                        frond_preview::units::bytes(t.output_bytes as f64),
                        if t.status == Status::UpToDate {
                            " (up to date)"
                        } else {
                            ""
                        }
                    ),
                };
                IndexEntry {
                    name: t.tree.clone(),
                    page,
                    thumbnail,
                    summary,
                    failed: t.status == Status::Failed,
                }
            })
            .collect();
        let bytes = self.trees.iter().map(|t| t.output_bytes).sum();
        index_page(
            &format!("frond batch: {}", self.input),
            &format!(
                "{} · {} built, {} up to date, {} failed",
                trees_line(self.trees.len(), Some(bytes)),
                self.counts.built,
                self.counts.up_to_date,
                self.counts.failed,
            ),
            &entries,
        )
    }

    fn csv(&self) -> Result<Vec<u8>> {
        let mut w = csv::Writer::from_writer(Vec::new());
        // The metrics any LOD has, in their order.
        let metric_names: Vec<LodMetric> = self
            .trees
            .iter()
            .flat_map(|t| t.lods.iter().flat_map(|l| l.metrics.keys().copied()))
            .collect::<std::collections::BTreeSet<LodMetric>>()
            .into_iter()
            .collect();
        let mut header: Vec<String> = [
            "tree",
            "output",
            "status",
            "reason",
            "input_hash",
            "params_hash",
            "preset",
            "settings",
            "files",
            "output_bytes",
            "methods",
            "screen_heights",
            "triangles",
            "billboards",
            "bones",
            "texture_bytes",
            "warnings",
            "sample_s",
            "build_s",
            "export_s",
            "eval_s",
            "wall_s",
            "peak_rss_mb",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        header.extend(metric_names.iter().map(|m| m.key().to_string()));
        w.write_record(&header).context("writing summary.csv")?;
        for t in &self.trees {
            // LOD values joined by ';', LOD0 first.
            let join =
                |f: &dyn Fn(&LodLine) -> String| t.lods.iter().map(f).collect::<Vec<_>>().join(";");
            let time = |k: &str| {
                t.times_s
                    .get(k)
                    .map(|v| format!("{v:.3}"))
                    .unwrap_or_default()
            };
            let mut row = vec![
                text_cell(&t.tree).into_owned(),
                text_cell(&t.output).into_owned(),
                serde_json::to_value(t.status)
                    .ok()
                    .and_then(|v| v.as_str().map(str::to_string))
                    .unwrap_or_default(),
                text_cell(t.reason.as_deref().unwrap_or_default()).into_owned(),
                t.input_hash.clone().unwrap_or_default(),
                t.params_hash.clone(),
                text_cell(t.preset.as_deref().unwrap_or_default()).into_owned(),
                text_cell(
                    &t.settings
                        .as_ref()
                        .and_then(|s| serde_json::to_string(s).ok())
                        .unwrap_or_default(),
                )
                .into_owned(),
                t.files.len().to_string(),
                t.output_bytes.to_string(),
                text_cell(&join(&|l| l.method.clone())).into_owned(),
                join(&|l| l.screen_height.map(|h| h.to_string()).unwrap_or_default()),
                join(&|l| l.triangles.to_string()),
                join(&|l| l.billboards.to_string()),
                join(&|l| l.bones.to_string()),
                join(&|l| l.texture_bytes.to_string()),
                text_cell(&t.warnings.join(" | ")).into_owned(),
                time("sample"),
                time("build"),
                time("export"),
                time("eval"),
                format!("{:.3}", t.wall_s),
                t.peak_rss_bytes
                    .map(|b| format!("{:.1}", b as f64 / 1_048_576.0))
                    .unwrap_or_default(),
            ];
            for m in &metric_names {
                row.push(join(&|l| {
                    l.metric(*m).map(|v| format!("{v:.5}")).unwrap_or_default()
                }));
            }
            w.write_record(&row).context("writing summary.csv")?;
        }
        w.into_inner().context("writing summary.csv")
    }
}

/// Reads a summary JSON.
pub fn read_summary(path: &Path) -> Result<BatchSummary> {
    let bytes = std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))?;
    serde_json::from_slice(&bytes)
        .with_context(|| format!("{}: not a frond batch summary", path.display()))
}

/// The summaries in `dir`: `summary.shard-*.json` if any, else `summary.json`.
pub fn summaries_in(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut shards: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: cannot list", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name().is_some_and(|n| {
                let n = n.to_string_lossy();
                n.starts_with("summary.shard-") && n.ends_with(".json")
            })
        })
        .collect();
    shards.sort();
    if shards.is_empty() {
        let single = dir.join("summary.json");
        if !single.is_file() {
            bail!("{}: no summary.json or summary.shard-*.json", dir.display());
        }
        shards.push(single);
    }
    Ok(shards)
}

/// Merges shard summaries into one: every tree once (a tree two shards both list is an
/// error), sorted; warns about shards of a count that are missing.
pub fn merge(parts: &[(PathBuf, BatchSummary)]) -> Result<(BatchSummary, Vec<String>)> {
    let Some((_, first)) = parts.first() else {
        bail!("nothing to merge");
    };
    let mut warnings = Vec::new();
    let mut trees: BTreeMap<String, (TreeEntry, &Path)> = BTreeMap::new();
    for (path, s) in parts {
        if s.input != first.input || s.preset != first.preset {
            warnings.push(format!(
                "{}: input '{}' preset {:?} differ from the first summary's ('{}', {:?})",
                path.display(),
                s.input,
                s.preset,
                first.input,
                first.preset
            ));
        }
        for t in &s.trees {
            if let Some((_, other)) = trees.get(&t.tree) {
                bail!(
                    "tree '{}' is in both {} and {} (shards of different counts?)",
                    t.tree,
                    other.display(),
                    path.display()
                );
            }
            trees.insert(t.tree.clone(), (t.clone(), path));
        }
    }
    let mut counts_seen: BTreeMap<u64, Vec<u64>> = BTreeMap::new();
    for (_, s) in parts {
        if let Some(sh) = s.shard {
            counts_seen.entry(sh.count).or_default().push(sh.index);
        }
    }
    for (count, mut seen) in counts_seen {
        seen.sort();
        seen.dedup();
        let missing: Vec<u64> = (0..count).filter(|i| !seen.contains(i)).collect();
        if !missing.is_empty() {
            warnings.push(format!(
                "shards {missing:?} of {count} are missing: their trees are not in the summary"
            ));
        }
    }
    let trees: Vec<TreeEntry> = trees.into_values().map(|(t, _)| t).collect();
    let summary = BatchSummary {
        frond: first.frond.clone(),
        input: first.input.clone(),
        preset: first.preset.clone(),
        shard: None,
        merged_from: parts.iter().map(|(p, _)| p.display().to_string()).collect(),
        counts: Counts::of(&trees),
        trees,
        wall_s: parts.iter().map(|(_, s)| s.wall_s).fold(0.0, f64::max),
        jobs: parts.iter().map(|(_, s)| s.jobs).sum(),
    };
    Ok((summary, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lod_metrics_read_back_by_their_keys_in_order() {
        let keys: Vec<&str> = LodMetric::ALL.iter().map(|m| m.key()).collect();
        assert_eq!(
            keys,
            [
                "coverage_static",
                "coverage_animated",
                "coverage_ratio",
                "coverage_binary",
                "coverage_foliage",
                "colour_difference",
                "projected_distance",
                "orientation",
                "dominating_axis",
            ]
        );
        let mut sorted = LodMetric::ALL;
        sorted.sort();
        assert_eq!(sorted, LodMetric::ALL, "ALL is in declaration order");
        let line = LodLine {
            file: "t_LOD1.glb".into(),
            screen_height: Some(60.0),
            method: "cards".into(),
            triangles: 10,
            billboards: 0,
            bones: 1,
            texture_bytes: 4,
            metrics: LodMetric::ALL
                .into_iter()
                .enumerate()
                .map(|(k, m)| (m, (k != 3).then_some(k as f64 / 8.0)))
                .collect(),
        };
        let json = serde_json::to_string(&line).unwrap();
        assert!(
            json.contains(r#""metrics":{"coverage_static":0.0,"coverage_animated":0.125,"coverage_ratio":0.25,"coverage_binary":null,"#),
            "{json}"
        );
        let back: LodLine = serde_json::from_str(&json).unwrap();
        assert_eq!(back, line);
        assert_eq!(back.metric(LodMetric::CoverageRatio), Some(0.25));
        assert_eq!(back.metric(LodMetric::CoverageBinary), None);
        // A line of a summary from before the filtered coverage error (its static error was
        // `coverage`) does not read: its tree's stamp is not up to date.
        let old = json.replace("\"coverage_static\"", "\"coverage\"");
        let err = serde_json::from_str::<LodLine>(&old).unwrap_err();
        assert!(
            err.to_string()
                .contains("'coverage' is not a summary metric"),
            "{err}"
        );
    }

    #[test]
    fn the_csv_has_a_column_per_metric_any_lod_has() {
        let line = |metrics: &[(LodMetric, Option<f64>)]| LodLine {
            file: "x.glb".into(),
            screen_height: None,
            method: "input".into(),
            triangles: 0,
            billboards: 0,
            bones: 0,
            texture_bytes: 0,
            metrics: metrics.iter().copied().collect(),
        };
        let tree = TreeEntry {
            lods: vec![
                line(&[]),
                line(&[
                    (LodMetric::CoverageRatio, Some(0.875)),
                    (LodMetric::CoverageAnimated, Some(0.0625)),
                ]),
            ],
            status: Status::Built,
            ..TreeEntry::failed(
                &super::super::inputs::TreeInput {
                    path: "t.glb".into(),
                    relative: "t.glb".into(),
                    output: "t".into(),
                    overrides: Default::default(),
                },
                "",
            )
        };
        let summary = BatchSummary {
            frond: "0".into(),
            input: "lib".into(),
            preset: None,
            shard: None,
            merged_from: Vec::new(),
            counts: Counts::of(std::slice::from_ref(&tree)),
            trees: vec![tree],
            wall_s: 0.0,
            jobs: 1,
        };
        let csv = String::from_utf8(summary.csv().unwrap()).unwrap();
        let mut lines = csv.lines();
        let header: Vec<&str> = lines.next().unwrap().split(',').collect();
        assert_eq!(
            header[header.len() - 2..],
            ["coverage_animated", "coverage_ratio"]
        );
        let row = lines.next().unwrap();
        assert!(row.ends_with(",;0.06250,;0.87500"), "{row}");
    }
}
