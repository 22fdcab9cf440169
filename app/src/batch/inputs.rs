//! The trees of a batch: every `.glb`/`.gltf` below a folder, or the `[[tree]]` entries of a TOML
//! manifest with per-tree overrides; and the hash of each tree's input files.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use frond_scene::InputLimits;
use frond_scene::input_file::{read_regular_file, resolve_uri};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};

use crate::lod_settings::{Animation, MethodChoice, Named};

/// Settings a manifest may give every tree (`[defaults]`) or one tree (`[[tree]]`).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Overrides {
    /// `frond lod`'s LOD method by name (one of [`MethodChoice::list`]).
    pub method: Option<String>,
    /// Screen heights in pixels, nearest first.
    pub lods: Option<Vec<f32>>,
    /// How billboards are animated, by name (one of [`Animation::list`]).
    pub animation: Option<String>,
    /// Materials read as foliage whatever their names say.
    pub foliage_material: Option<Vec<String>>,
    /// Materials read as wood whatever their names say.
    pub wood_material: Option<Vec<String>>,
    /// Clip to sample (None: the first).
    pub clip: Option<String>,
    /// Random seed of the build: same input, settings and seed, same files.
    pub seed: Option<u64>,
    /// Uniform animation samples over the loop.
    pub samples: Option<usize>,
    /// Screen-space error budget in pixels, from which each LOD's ε is derived.
    pub pixel_error: Option<f32>,
    /// Skeleton methods: billboard clouds per LOD.
    pub clouds: Option<u64>,
    /// Spectral methods: animation clusters per LOD.
    pub clusters: Option<u64>,
}

impl Overrides {
    /// `self` where set, else `base`.
    pub fn or(&self, base: &Overrides) -> Overrides {
        Overrides {
            method: self.method.clone().or_else(|| base.method.clone()),
            lods: self.lods.clone().or_else(|| base.lods.clone()),
            animation: self.animation.clone().or_else(|| base.animation.clone()),
            foliage_material: self
                .foliage_material
                .clone()
                .or_else(|| base.foliage_material.clone()),
            wood_material: self
                .wood_material
                .clone()
                .or_else(|| base.wood_material.clone()),
            clip: self.clip.clone().or_else(|| base.clip.clone()),
            seed: self.seed.or(base.seed),
            samples: self.samples.or(base.samples),
            pixel_error: self.pixel_error.or(base.pixel_error),
            clouds: self.clouds.or(base.clouds),
            clusters: self.clusters.or(base.clusters),
        }
    }

    /// Refuses names and values `frond lod` would refuse, naming `what` (the manifest entry).
    pub fn check(&self, what: &str) -> Result<()> {
        if let Some(m) = &self.method
            && MethodChoice::parse(m).is_none()
        {
            bail!(
                "{what}: unknown method '{m}' (one of {})",
                MethodChoice::list()
            );
        }
        if let Some(a) = &self.animation
            && Animation::parse(a).is_none()
        {
            bail!(
                "{what}: unknown animation '{a}' (one of {})",
                Animation::list()
            );
        }
        if let Some(l) = &self.lods {
            if l.is_empty() {
                bail!("{what}: lods is empty");
            }
            if let Some(h) = l.iter().find(|h| !(h.is_finite() && **h >= 1.0)) {
                bail!("{what}: lods: {h} is not a screen height of at least 1 pixel");
            }
        }
        if let Some(p) = self.pixel_error
            && !(p.is_finite() && p > 0.0)
        {
            bail!("{what}: pixel_error {p} is not positive");
        }
        if self.samples == Some(0) || self.clouds == Some(0) || self.clusters == Some(0) {
            bail!("{what}: samples, clouds and clusters must be at least 1");
        }
        Ok(())
    }
}

/// One tree of the batch.
#[derive(Clone, Debug)]
pub struct TreeInput {
    /// Its path relative to INPUT (the manifest's folder for a manifest), `/`-separated: the
    /// tree's name in summaries and the key of `--shard`.
    pub relative: String,
    /// The tree file as it is opened: under INPUT, or the manifest entry's path resolved
    /// against the manifest's folder.
    pub path: PathBuf,
    /// Output folder relative to OUTDIR: `relative` without its extension (or the manifest's
    /// `output`).
    pub output: String,
    /// The manifest's settings for it (with its `[defaults]`); empty for a folder.
    pub overrides: Overrides,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct Manifest {
    #[serde(default)]
    defaults: Overrides,
    #[serde(default)]
    tree: Vec<ManifestTree>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestTree {
    path: PathBuf,
    output: Option<String>,
    #[serde(flatten)]
    settings: Overrides,
}

/// The trees of INPUT (a folder or a `.toml` manifest), sorted by relative path. Folders skip
/// hidden entries and `skip` (the output folder when it lies inside INPUT).
pub fn discover(input: &Path, skip: Option<&Path>) -> Result<Vec<TreeInput>> {
    let meta = std::fs::metadata(input)
        .with_context(|| format!("{}: cannot read the batch input", input.display()))?;
    let mut trees = if meta.is_dir() {
        let mut found = Vec::new();
        walk(input, input, skip, &mut found)?;
        found
    } else if has_extension(input, "toml") {
        read_manifest(input)?
    } else {
        bail!(
            "{}: a batch input is a folder of .glb/.gltf files or a .toml manifest",
            input.display()
        );
    };
    trees.sort_by(|a, b| a.relative.cmp(&b.relative));
    for pair in trees.windows(2) {
        if pair[0].relative == pair[1].relative {
            bail!(
                "{}: tree '{}' is listed twice",
                input.display(),
                pair[0].relative
            );
        }
    }
    // Output folders must be distinct and none inside another (rebuilding the outer one would
    // move the inner one away).
    let by_output: std::collections::HashMap<&str, &str> = trees
        .iter()
        .map(|t| (t.output.as_str(), t.relative.as_str()))
        .collect();
    for t in &trees {
        if by_output.get(t.output.as_str()) != Some(&t.relative.as_str()) {
            bail!(
                "{}: '{}' and '{}' would both write OUTDIR/{}/ (rename one, or give a manifest \
                 `output`)",
                input.display(),
                by_output[t.output.as_str()],
                t.relative,
                t.output
            );
        }
        let mut prefix = t.output.as_str();
        while let Some((outer, _)) = prefix.rsplit_once('/') {
            if let Some(other) = by_output.get(outer) {
                bail!(
                    "{}: '{}' would write OUTDIR/{}/ inside OUTDIR/{outer}/, the output of '{other}' \
                     (give a manifest `output`)",
                    input.display(),
                    t.relative,
                    t.output
                );
            }
            prefix = outer;
        }
    }
    if trees.is_empty() {
        bail!("{}: no .glb or .gltf file in it", input.display());
    }
    Ok(trees)
}

fn has_extension(path: &Path, ext: &str) -> bool {
    path.extension()
        .is_some_and(|e| e.to_string_lossy().eq_ignore_ascii_case(ext))
}

fn is_tree_file(path: &Path) -> bool {
    has_extension(path, "glb") || has_extension(path, "gltf")
}

/// `path` relative to `root`, `/`-separated.
fn relative_name(root: &Path, path: &Path) -> Option<String> {
    let rel = path.strip_prefix(root).ok()?;
    let parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    (!parts.is_empty()).then(|| parts.join("/"))
}

/// `relative` without the file extension.
fn without_extension(relative: &str) -> String {
    let (folder, file) = match relative.rsplit_once('/') {
        Some((d, f)) => (Some(d), f),
        None => (None, relative),
    };
    let stem = match file.rsplit_once('.') {
        Some((stem, _)) if !stem.is_empty() => stem,
        _ => file,
    };
    match folder {
        Some(d) => format!("{d}/{stem}"),
        None => stem.to_string(),
    }
}

fn walk(root: &Path, dir: &Path, skip: Option<&Path>, out: &mut Vec<TreeInput>) -> Result<()> {
    let entries =
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot list", dir.display()))?;
    for entry in entries {
        let entry = entry.with_context(|| format!("{}: cannot list", dir.display()))?;
        let path = entry.path();
        if entry.file_name().to_string_lossy().starts_with('.') {
            continue;
        }
        if let Some(skip) = skip
            && std::fs::canonicalize(&path).is_ok_and(|c| c == skip)
        {
            continue;
        }
        // Symbolic links to folders are not followed (no cycles); links to files are.
        let kind = entry
            .file_type()
            .with_context(|| format!("{}: cannot stat", path.display()))?;
        if kind.is_dir() {
            walk(root, &path, skip, out)?;
        } else if is_tree_file(&path)
            && let Some(relative) = relative_name(root, &path)
        {
            out.push(TreeInput {
                output: without_extension(&relative),
                relative,
                path,
                overrides: Overrides::default(),
            });
        }
    }
    Ok(())
}

fn read_manifest(path: &Path) -> Result<Vec<TreeInput>> {
    let text = std::fs::read_to_string(path)
        .with_context(|| format!("{}: cannot read the manifest", path.display()))?;
    let manifest: Manifest = toml::from_str(&text)
        .with_context(|| format!("{}: not a batch manifest", path.display()))?;
    let base = path.parent().unwrap_or(Path::new("."));
    manifest
        .defaults
        .check(&format!("{} [defaults]", path.display()))?;
    if manifest.tree.is_empty() {
        bail!("{}: the manifest lists no [[tree]]", path.display());
    }
    manifest
        .tree
        .into_iter()
        .enumerate()
        .map(|(i, t)| {
            let what = format!("{} tree {} ({})", path.display(), i + 1, t.path.display());
            t.settings.check(&what)?;
            let full = base.join(&t.path);
            // A path below the manifest's folder is named relative to it; any other (absolute,
            // or with `..`) by the path as written, its output folder by its file name.
            let below = t.path.is_relative()
                && t.path.components().all(|c| {
                    matches!(
                        c,
                        std::path::Component::Normal(_) | std::path::Component::CurDir
                    )
                });
            let (relative, default_output) = match relative_name(base, &full) {
                Some(r) if below => {
                    let o = without_extension(&r);
                    (r, o)
                }
                _ => {
                    let file = full
                        .file_name()
                        .map(|f| f.to_string_lossy().into_owned())
                        .with_context(|| format!("{what}: not a file path"))?;
                    (
                        t.path.to_string_lossy().replace('\\', "/"),
                        without_extension(&file),
                    )
                }
            };
            let output = match t.output {
                Some(o) => {
                    // Normal parts only, rejoined: `x/`, `x/.` and `x` are one folder.
                    let parts: Option<Vec<String>> = Path::new(&o)
                        .components()
                        .filter(|c| !matches!(c, std::path::Component::CurDir))
                        .map(|c| match c {
                            std::path::Component::Normal(n) => {
                                Some(n.to_string_lossy().into_owned())
                            }
                            _ => None,
                        })
                        .collect();
                    match parts {
                        Some(p) if !p.is_empty() && !p[0].starts_with(".frond-") => p.join("/"),
                        _ => bail!(
                            "{what}: output '{o}' must be a relative folder without '..' (and not \
                             one of frond's own .frond-* folders)"
                        ),
                    }
                }
                None => default_output,
            };
            Ok(TreeInput {
                relative,
                path: full,
                output,
                overrides: t.settings.or(&manifest.defaults),
            })
        })
        .collect()
}

/// SHA-256 (hex) of a tree's input: the file, and for a `.gltf` the external buffers and images
/// it references (so a changed `.bin` rebuilds the tree). Every file is read by the importer's
/// own rules ([`frond_scene::input_file`]: regular files inside the input's folder, within
/// `limits`), so a URI the import would refuse is never opened here either: a FIFO, a device or
/// `../../etc/passwd` is hashed as its refusal and the tree's import then fails saying why.
pub fn input_hash(path: &Path, limits: &InputLimits) -> Result<String> {
    let bytes = read_regular_file(path, limits.max_input_bytes)
        .map_err(|r| anyhow::anyhow!("{}: {r}", path.display()))?;
    let mut hasher = Sha256::new();
    hasher.update(&bytes);
    if has_extension(path, "gltf")
        && let Ok(doc) = serde_json::from_slice::<serde_json::Value>(&bytes)
    {
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut total = bytes.len() as u64;
        for key in ["buffers", "images"] {
            let uris = doc[key].as_array().into_iter().flatten();
            for uri in uris.filter_map(|b| b["uri"].as_str()) {
                if uri.starts_with("data:") {
                    continue;
                }
                hasher.update(uri.as_bytes());
                let read = resolve_uri(dir, uri)
                    .ok()
                    .and_then(|full| read_regular_file(&full, limits.max_input_bytes).ok());
                match read {
                    Some(b) if total.saturating_add(b.len() as u64) <= limits.max_input_bytes => {
                        total += b.len() as u64;
                        hasher.update((b.len() as u64).to_le_bytes());
                        hasher.update(&b);
                    }
                    Some(_) => hasher.update(b"<over the input size limit>"),
                    None => hasher.update(b"<refused or missing>"),
                }
            }
        }
    }
    Ok(hex(&hasher.finalize()))
}

/// Lower-case hex of bytes.
pub fn hex(bytes: &[u8]) -> String {
    bytes.iter().map(|b| format!("{b:02x}")).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn folder_and_manifest() {
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path();
        std::fs::create_dir_all(root.join("a/b")).unwrap();
        std::fs::create_dir_all(root.join(".hidden")).unwrap();
        for f in [
            "x.glb",
            "a/y.GLTF",
            "a/b/z.glb",
            "a/notes.txt",
            ".hidden/h.glb",
        ] {
            std::fs::write(root.join(f), b"-").unwrap();
        }
        let trees = discover(root, None).unwrap();
        let names: Vec<(&str, &str)> = trees
            .iter()
            .map(|t| (t.relative.as_str(), t.output.as_str()))
            .collect();
        assert_eq!(
            names,
            [("a/b/z.glb", "a/b/z"), ("a/y.GLTF", "a/y"), ("x.glb", "x")]
        );
        assert_eq!(without_extension("v1.2/tree"), "v1.2/tree");
        assert_eq!(without_extension("v1.2/tree.glb"), "v1.2/tree");
        std::fs::create_dir_all(root.join("x")).unwrap();
        std::fs::write(root.join("x/inner.glb"), b"-").unwrap();
        let err = discover(root, None).unwrap_err().to_string();
        assert!(err.contains("inside OUTDIR/x/"), "{err}");
        std::fs::remove_dir_all(root.join("x")).unwrap();
        let empty = tempfile::tempdir().unwrap();
        let err = discover(empty.path(), None).unwrap_err().to_string();
        assert!(err.contains("no .glb or .gltf"), "{err}");
        std::fs::write(root.join("x.gltf"), b"-").unwrap();
        let err = discover(root, None).unwrap_err().to_string();
        assert!(err.contains("would both write OUTDIR/x/"), "{err}");

        let m = root.join("m.toml");
        std::fs::write(
            &m,
            "[defaults]\nmethod = \"static\"\nlods = [200, 60]\n\n[[tree]]\npath = \"x.glb\"\n\
             \n[[tree]]\npath = \"a/b/z.glb\"\noutput = \"zed\"\nmethod = \"skeleton\"\n",
        )
        .unwrap();
        let trees = discover(&m, None).unwrap();
        assert_eq!(trees[0].relative, "a/b/z.glb");
        assert_eq!(trees[0].output, "zed");
        assert_eq!(trees[0].overrides.method.as_deref(), Some("skeleton"));
        assert_eq!(trees[0].overrides.lods, Some(vec![200.0, 60.0]));
        assert_eq!(trees[1].overrides.method.as_deref(), Some("static"));
        std::fs::write(&m, "[[tree]]\npath = \"x.glb\"\noutput = \"q/./\"\n[[tree]]\npath = \"a/y.GLTF\"\noutput = \"q\"\n").unwrap();
        let err = discover(&m, None).unwrap_err().to_string();
        assert!(err.contains("would both write OUTDIR/q/"), "{err}");
        std::fs::write(&m, "[[tree]]\npath = \"x.glb\"\noutput = \".frond-tmp\"\n").unwrap();
        let err = format!("{:#}", discover(&m, None).unwrap_err());
        assert!(err.contains("frond's own"), "{err}");
        // Paths outside the manifest's folder keep their written name, and never lead the
        // output folder outside OUTDIR.
        let sub = root.join("a/m.toml");
        std::fs::write(
            &sub,
            "[[tree]]\npath = \"../x.glb\"\n[[tree]]\npath = \"/abs/y.gltf\"\n",
        )
        .unwrap();
        let trees = discover(&sub, None).unwrap();
        let names: Vec<(&str, &str)> = trees
            .iter()
            .map(|t| (t.relative.as_str(), t.output.as_str()))
            .collect();
        assert_eq!(names, [("../x.glb", "x"), ("/abs/y.gltf", "y")]);
        std::fs::write(&m, "[[tree]]\npath = \"x.glb\"\nmethod = \"magic\"\n").unwrap();
        let err = format!("{:#}", discover(&m, None).unwrap_err());
        assert!(err.contains("unknown method 'magic'"), "{err}");
        std::fs::write(&m, "[[tree]]\npath = \"x.glb\"\ncolour = 1\n").unwrap();
        let err = format!("{:#}", discover(&m, None).unwrap_err());
        assert!(err.contains("not a batch manifest"), "{err}");
    }

    #[test]
    fn gltf_hash_covers_its_buffers() {
        let dir = tempfile::tempdir().unwrap();
        let g = dir.path().join("t.gltf");
        std::fs::write(&g, br#"{"buffers":[{"uri":"t%20b.bin","byteLength":1}]}"#).unwrap();
        std::fs::write(dir.path().join("t b.bin"), b"1").unwrap();
        let h1 = input_hash(&g, &InputLimits::default()).unwrap();
        std::fs::write(dir.path().join("t b.bin"), b"2").unwrap();
        let h2 = input_hash(&g, &InputLimits::default()).unwrap();
        assert_ne!(h1, h2);
        assert_eq!(h2, input_hash(&g, &InputLimits::default()).unwrap());
        assert_eq!(h1.len(), 64);
    }
}
