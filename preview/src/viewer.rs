//! The live view: three.js, vendored (see `preview/vendor/README.md`), playing the run's
//! combined file in the page, with a LOD slider, play/pause and switching by screen size.
//!
//! How the page reaches the GLB: browsers refuse a page opened from disk (`file://`) any read
//! of the files beside it, and refuse ES modules there too. So the three.js bundle is one
//! classic script (runs from disk), and the combined file is either fetched when the folder is
//! served over HTTP (`frond view OUTDIR` does that on localhost and opens the page; any static
//! server works) or picked by the user with a file button on a page opened from disk. The GLBs
//! are referenced, never copied into the page: the page stays small and shows what was written.

use serde::Serialize;

/// The folder, beside the pages, that holds the vendored scripts (the same bytes for every
/// tree, so trees sharing an output folder share it).
pub const VIEWER_DIR: &str = "viewer";

/// three.js r187 with GLTFLoader, KTX2Loader, OrbitControls and meshoptimizer's decoder.
const THREE: &[u8] = include_bytes!("../vendor/frond-three.js");
const THREE_LICENSE: &[u8] = include_bytes!("../vendor/LICENSE-three");
const BASIS_JS: &[u8] = include_bytes!("../vendor/basis_transcoder.js");
const BASIS_WASM: &[u8] = include_bytes!("../vendor/basis_transcoder.wasm");

/// The page's script driving the view (classic script; reads `#frond-config`).
pub(crate) const LIVE_VIEW_JS: &str = include_str!("../assets/live_view.js");

/// The vendored files a page needs, as (path relative to the output folder, bytes): three.js
/// always, Basis Universal's transcoder only when the files carry KTX2 textures.
pub fn viewer_files(ktx2: bool) -> Vec<(String, &'static [u8])> {
    let mut files = vec![
        (format!("{VIEWER_DIR}/frond-three.js"), THREE),
        (format!("{VIEWER_DIR}/LICENSE-three"), THREE_LICENSE),
    ];
    if ktx2 {
        files.push((format!("{VIEWER_DIR}/basis_transcoder.js"), BASIS_JS));
        files.push((format!("{VIEWER_DIR}/basis_transcoder.wasm"), BASIS_WASM));
    }
    files
}

/// What the live view's script is told (`<script type="application/json" id="frond-config">`).
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct ViewConfig {
    /// The combined file, relative to the page.
    pub combined: String,
    /// The clip to play.
    pub clip: Option<String>,
    /// Where the vendored scripts are, relative to the page.
    pub viewer: String,
    /// The files carry KTX2 textures (the transcoder is beside the page).
    pub ktx2: bool,
    /// The chain's LODs, LOD0 first.
    pub lods: Vec<ViewLod>,
}

/// One LOD of the combined file.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct ViewLod {
    /// The LOD's own file, relative to the page.
    pub file: String,
    /// The combined file's scene root nodes that are this LOD.
    pub nodes: Vec<String>,
    /// The screen height it was built for (None: LOD0).
    pub screen_height: Option<f32>,
    /// The smallest tree height in pixels it is shown at when switching by screen size (the
    /// report's `min_screen_fraction` times `--resolution`).
    pub shown_down_to_px: f32,
    /// Triangles the LOD draws (as its file costs, where measured).
    pub triangles: u64,
    /// Vertex-animated (VAT or spectral): three.js plays it still, without its shader.
    pub vertex_animated: bool,
}

/// The JSON of a config, safe inside a `<script>` element: [`script_json`].
pub(crate) fn config_json(config: &ViewConfig) -> String {
    script_json(&serde_json::to_string(config).unwrap_or_else(|_| "{}".into()))
}

/// JSON text made safe to embed in an HTML `<script>` element: every `<`, `>` and `&` written
/// as a `\u` escape, so no name can end the element (`</script>`) or open a comment (`<!--`,
/// which puts the HTML parser in its "script data escaped" state and can swallow the rest of
/// the page); U+2028 and U+2029 escaped too, for scripts that read the text as JavaScript.
/// Only string contents can hold these characters, where the escapes mean the same.
pub fn script_json(json: &str) -> String {
    let mut out = String::with_capacity(json.len());
    for c in json.chars() {
        match c {
            '<' => out.push_str("\\u003c"),
            '>' => out.push_str("\\u003e"),
            '&' => out.push_str("\\u0026"),
            '\u{2028}' => out.push_str("\\u2028"),
            '\u{2029}' => out.push_str("\\u2029"),
            c => out.push(c),
        }
    }
    out
}

/// The scene root node names of a GLB's default scene, grouped by the LOD they belong to: the
/// export names each LOD's roots `…_LOD<k>` or `…_LOD<k>_rig`. `lods` groups are returned.
pub fn combined_roots(glb: &[u8], lods: usize) -> Result<Vec<Vec<String>>, String> {
    let json = glb_json(glb)?;
    let scene = json["scene"].as_u64().unwrap_or(0) as usize;
    let roots = json["scenes"][scene]["nodes"]
        .as_array()
        .ok_or("the file has no scene")?;
    let mut groups = vec![Vec::new(); lods];
    for r in roots {
        let Some(name) = r
            .as_u64()
            .and_then(|i| json["nodes"][i as usize]["name"].as_str())
        else {
            continue;
        };
        let stem = name.strip_suffix("_rig").unwrap_or(name);
        let k = stem
            .rsplit_once("_LOD")
            .and_then(|(_, k)| k.parse::<usize>().ok());
        if let Some(g) = k.and_then(|k| groups.get_mut(k)) {
            g.push(name.to_string());
        }
    }
    if let Some(k) = groups.iter().position(Vec::is_empty) {
        return Err(format!("no scene root node is LOD{k}'s (named …_LOD{k})"));
    }
    Ok(groups)
}

/// Whether a GLB lists `extension` among the extensions it uses (the KTX2 transcoder is only
/// written for files that need it).
pub fn uses_extension(glb: &[u8], extension: &str) -> Result<bool, String> {
    let json = glb_json(glb)?;
    Ok(json["extensionsUsed"]
        .as_array()
        .is_some_and(|a| a.iter().any(|e| e.as_str() == Some(extension))))
}

/// A GLB's JSON chunk.
fn glb_json(glb: &[u8]) -> Result<serde_json::Value, String> {
    let word = |at: usize| {
        glb.get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize)
    };
    if glb.get(0..4) != Some(b"glTF") {
        return Err("not a GLB".into());
    }
    let (Some(len), Some(kind)) = (word(12), word(16)) else {
        return Err("truncated GLB header".into());
    };
    if kind != 0x4E4F_534A {
        return Err("the GLB's first chunk is not JSON".into());
    }
    let chunk = glb.get(20..20 + len).ok_or("truncated JSON chunk")?;
    serde_json::from_slice(chunk).map_err(|e| format!("bad JSON chunk: {e}"))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn glb(json: &str) -> Vec<u8> {
        let mut j = json.as_bytes().to_vec();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        let mut out = b"glTF".to_vec();
        out.extend(2u32.to_le_bytes());
        out.extend((20 + j.len() as u32).to_le_bytes());
        out.extend((j.len() as u32).to_le_bytes());
        out.extend(0x4E4F_534Au32.to_le_bytes());
        out.extend(j);
        out
    }

    #[test]
    fn roots_are_grouped_by_their_lod_suffix() {
        let file = glb(
            r#"{"scenes":[{"nodes":[0,1,2,3]}],"nodes":[{"name":"oak_LOD0_rig"},
            {"name":"oak_LOD1_rig"},{"name":"LOD_oak_LOD0"},{"name":"LOD_oak_LOD1"}]}"#,
        );
        let groups = combined_roots(&file, 2).expect("groups");
        assert_eq!(groups[0], ["oak_LOD0_rig", "LOD_oak_LOD0"]);
        assert_eq!(groups[1], ["oak_LOD1_rig", "LOD_oak_LOD1"]);
        let err = combined_roots(&file, 3).expect_err("LOD2 missing");
        assert!(err.contains("LOD2"), "{err}");
        assert!(combined_roots(b"nope", 1).is_err());
    }

    #[test]
    fn config_cannot_close_its_script_element() {
        let c = ViewConfig {
            combined: "a</script>.glb".into(),
            clip: None,
            viewer: VIEWER_DIR.into(),
            ktx2: false,
            lods: Vec::new(),
        };
        assert!(!config_json(&c).contains("</"));
    }

    #[test]
    fn script_json_keeps_every_name_inside_its_element() {
        let name = "Wind<!--<script></script>&\u{2028}";
        let json = serde_json::to_string(&serde_json::json!({ "clip": name })).unwrap();
        let safe = script_json(&json);
        assert!(!safe.contains(['<', '>', '&', '\u{2028}']), "{safe}");
        let back: serde_json::Value = serde_json::from_str(&safe).unwrap();
        assert_eq!(back["clip"], name);
    }
}
