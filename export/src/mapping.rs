//! The `<name>_LOD<k>.mapping.json` sidecar: for every billboard, the input foliage triangles it
//! replaces (indices in the input's triangle order), what it follows and whether it has its own
//! motion. The metrics read it to compare a LOD with the original, triangle by triangle.

use frond_lod::AnimatedBillboardCloud;
use serde::{Deserialize, Serialize};

/// One billboard's entry.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct BillboardMapping {
    /// Billboard index: quads appear in this order in the LOD's billboard primitives (4
    /// vertices and 6 indices each; the baked billboards' primitive first, then one per input
    /// material for billboards that copy an input card).
    pub billboard: usize,
    /// Input triangle indices (the input file's triangle order, as `frond inspect` counts them).
    pub triangles: Vec<usize>,
    /// Name of the rig node it follows, if any.
    pub follows: Option<String>,
    /// True when it has its own sampled motion (a `frond_motion_*` joint or VAT track).
    pub own_motion: bool,
}

/// The whole sidecar.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Mapping {
    /// The LOD's index in the chain (1 for `_LOD1`).
    pub lod: usize,
    /// The LOD's GLB, relative to the sidecar.
    pub file: String,
    /// The method that built the billboards (`per-bone`, `spectral`, ...).
    pub method: String,
    /// Input foliage triangles that no billboard replaces (dropped as too small to see).
    pub unmapped_triangles: Vec<usize>,
    /// Every billboard, in billboard order.
    pub billboards: Vec<BillboardMapping>,
}

impl Mapping {
    /// The mapping of `cloud`; `foliage` lists every input foliage triangle (to find the
    /// unmapped ones).
    pub fn of(
        cloud: &AnimatedBillboardCloud,
        lod: usize,
        file: &str,
        foliage: &[usize],
    ) -> Mapping {
        let mut mapped = std::collections::HashSet::new();
        let billboards = cloud
            .billboards
            .iter()
            .enumerate()
            .map(|(i, b)| {
                mapped.extend(b.triangles.iter().copied());
                BillboardMapping {
                    billboard: i,
                    triangles: b.triangles.clone(),
                    follows: b.follows.map(|n| cloud.rig.nodes[n].name.clone()),
                    own_motion: b.motion.is_some(),
                }
            })
            .collect();
        Mapping {
            lod,
            file: file.to_string(),
            method: cloud.method.clone(),
            unmapped_triangles: foliage
                .iter()
                .copied()
                .filter(|t| !mapped.contains(t))
                .collect(),
            billboards,
        }
    }
}
