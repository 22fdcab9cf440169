//! Skin influences: a skinned primitive's `JOINTS_n`/`WEIGHTS_n` sets read, merged per vertex
//! into the 4 influences a frond vertex carries, and normalised.

use gltf::json::mesh::Semantic;
use gltf::json::validation::Checked;

use crate::error::Result;
use crate::import::attributes::PrimitiveAttributes;
use crate::model::{Binding, Bone};

/// One primitive's influence sets, and what merging and normalising them per vertex did (for
/// the warnings that say so).
pub(super) struct Influences {
    /// The sets `JOINTS_n`/`WEIGHTS_n` for n = 0, 1, ... while both are present: (joint ids,
    /// weights), 4 per vertex each. Empty for an unskinned primitive (and a skinned one without
    /// `JOINTS_0`/`WEIGHTS_0`): every vertex is then bound to joint 0.
    sets: Vec<(Vec<u32>, Vec<f32>)>,
    /// Joints in the binding's palette (1 for a node binding): a non-zero weight must name one
    /// below this.
    palette: usize,
    /// One vertex's (joint, weight) pairs merged over several sets; reused between vertices.
    merged: Vec<(usize, f32)>,
    /// Vertices whose weights were all zero (bound rigidly to joint 0).
    zero_weight: usize,
    /// Vertices with more than 4 influences over the sets (their 4 largest kept).
    folded: usize,
    /// The largest share of one vertex's total weight dropped by keeping its 4 largest.
    max_dropped: f32,
}

impl Influences {
    /// Reads the influence sets of a primitive whose binding has `palette` joints; `skinned`
    /// says whether its node has a skin (an unskinned primitive's sets are not read).
    ///
    /// Refused: a `JOINTS_n`/`WEIGHTS_n` pair that is not VEC4 with one element per vertex.
    /// Accepted with a warning: a skinned primitive without `JOINTS_0`/`WEIGHTS_0` (bound to
    /// joint 0), and sets past the first gap or without their partner (ignored).
    pub(super) fn read(
        attrs: &PrimitiveAttributes,
        skinned: bool,
        palette: usize,
        warnings: &mut Vec<String>,
    ) -> Result<Self> {
        let (src, what, n) = (attrs.src, attrs.what, attrs.n);
        // Influence sets JOINTS_n/WEIGHTS_n for n = 0, 1, ... while both are present:
        // (joint ids, weights), 4 per vertex each.
        let mut influence_sets: Vec<(Vec<u32>, Vec<f32>)> = Vec::new();
        if skinned {
            while let (Some(j), Some(w)) = (
                attrs.accessor(Semantic::Joints(influence_sets.len() as u32)),
                attrs.accessor(Semantic::Weights(influence_sets.len() as u32)),
            ) {
                let set = influence_sets.len();
                let (jw, jv) = src.read_ints(j, &format!("{what} JOINTS_{set}"))?;
                let wd = attrs.read_counted(w, &format!("WEIGHTS_{set}"))?;
                if jw != 4 || wd.width != 4 || jv.len() != n * 4 {
                    return Err(src.invalid(format!(
                        "{what}: JOINTS_{set}/WEIGHTS_{set} must be VEC4 with one per vertex"
                    )));
                }
                influence_sets.push((jv, wd.values));
            }
            if influence_sets.is_empty() {
                warnings.push(format!(
                    "{what}: skinned node without JOINTS_0/WEIGHTS_0; bound to joint 0"
                ));
            }
            let mut unpaired: Vec<String> = attrs
                .primitive
                .attributes
                .keys()
                .filter_map(|k| match k {
                    Checked::Valid(sem @ (Semantic::Joints(s) | Semantic::Weights(s)))
                        if *s as usize >= influence_sets.len().max(1) =>
                    {
                        Some(sem.to_string())
                    }
                    _ => None,
                })
                .collect();
            unpaired.sort();
            if !unpaired.is_empty() {
                warnings.push(format!(
                    "{what}: {} ignored (influence sets are read as JOINTS_n/WEIGHTS_n pairs numbered from 0)",
                    unpaired.join(", ")
                ));
            }
        }
        Ok(Influences {
            sets: influence_sets,
            palette,
            merged: Vec::new(),
            zero_weight: 0,
            folded: 0,
            max_dropped: 0.0,
        })
    }

    /// Vertex `i`'s 4 joints and weights: with one set, its slots as written (zero-weight slots
    /// naming joint 0); with several, the influences merged per joint and the 4 largest kept.
    /// The weights are normalised to sum 1; all-zero weights bind the vertex to joint 0.
    ///
    /// Refused: a non-zero weight naming a joint past the palette, a negative or non-finite
    /// weight, and weights whose sum overflows.
    pub(super) fn vertex(
        &mut self,
        attrs: &PrimitiveAttributes,
        i: usize,
    ) -> Result<([u16; 4], [f32; 4])> {
        if self.sets.is_empty() {
            return Ok(([0; 4], [1.0, 0.0, 0.0, 0.0]));
        }
        let (src, what, palette) = (attrs.src, attrs.what, self.palette);
        let check = |jj: usize, w: f32| -> Result<()> {
            if w != 0.0 && jj >= palette {
                return Err(src.invalid(format!(
                    "{what}: vertex {i} names joint {jj}, but the skin has {palette} joints"
                )));
            }
            if !w.is_finite() || w < 0.0 {
                return Err(src.invalid(format!(
                    "{what}: vertex {i} has a negative or non-finite weight"
                )));
            }
            Ok(())
        };
        let mut j = [0u16; 4];
        let mut w = [0.0f32; 4];
        if let [(jv, wv)] = self.sets.as_slice() {
            // One set: slots kept as written (zero-weight slots name joint 0).
            for k in 0..4 {
                let (jj, wk) = (jv[i * 4 + k] as usize, wv[i * 4 + k]);
                check(jj, wk)?;
                j[k] = if wk == 0.0 { 0 } else { jj as u16 };
                w[k] = wk;
            }
        } else {
            // Several sets: merge per joint, keep the 4 largest.
            let influences = &mut self.merged;
            influences.clear();
            for (jv, wv) in &self.sets {
                for k in i * 4..i * 4 + 4 {
                    let (jj, wk) = (jv[k] as usize, wv[k]);
                    check(jj, wk)?;
                    if wk > 0.0 {
                        match influences.iter_mut().find(|e| e.0 == jj) {
                            Some(e) => e.1 += wk,
                            None => influences.push((jj, wk)),
                        }
                    }
                }
            }
            if influences.len() > 4 {
                influences.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
                let total: f32 = influences.iter().map(|e| e.1).sum();
                let dropped: f32 = influences[4..].iter().map(|e| e.1).sum();
                self.folded += 1;
                self.max_dropped = self.max_dropped.max(dropped / total);
                influences.truncate(4);
            }
            for (k, &(jj, wk)) in influences.iter().enumerate() {
                j[k] = jj as u16;
                w[k] = wk;
            }
        }
        let sum: f32 = w.iter().sum();
        if !sum.is_finite() {
            // Each weight is finite, but e.g. 4 × 1e38 is not: normalising would
            // silently zero them all.
            return Err(src.invalid(format!(
                "{what}: vertex {i} has skin weights whose sum overflows ({:?})",
                w
            )));
        }
        if sum > 0.0 {
            for x in &mut w {
                *x /= sum;
            }
        } else {
            self.zero_weight += 1;
            j = [0; 4];
            w = [1.0, 0.0, 0.0, 0.0];
        }
        Ok((j, w))
    }

    /// Warns, once every vertex is read, about vertices bound rigidly for want of weights and
    /// about extra influence sets merged (saying how much weight keeping 4 dropped).
    pub(super) fn warn(
        &self,
        attrs: &PrimitiveAttributes,
        binding: &Binding,
        bones: &[Bone],
        warnings: &mut Vec<String>,
    ) {
        let (what, n) = (attrs.what, attrs.n);
        let (zero_weight, folded, max_dropped) = (self.zero_weight, self.folded, self.max_dropped);
        if zero_weight > 0
            && let Binding::Skin { joints, .. } = binding
            && let Some(first) = joints.first().map(|&b| &bones[b])
        {
            warnings.push(format!(
                "{what}: {zero_weight} of {n} vertices {} all-zero skin weights; bound rigidly to the skin's first joint (joint 0, node {} '{}')",
                if zero_weight == 1 { "has" } else { "have" },
                first.node,
                first.name
            ));
        }
        if self.sets.len() > 1 {
            let extra: Vec<String> = (1..self.sets.len())
                .map(|s| format!("JOINTS_{s}/WEIGHTS_{s}"))
                .collect();
            let outcome = if folded == 0 {
                "no vertex has more than 4, so nothing is lost".to_string()
            } else {
                format!(
                    "{folded} {} more than 4 and {} the 4 largest, renormalised (dropping at most {:.1}% of a vertex's weight)",
                    if folded == 1 {
                        "vertex has"
                    } else {
                        "vertices have"
                    },
                    if folded == 1 { "keeps" } else { "keep" },
                    max_dropped * 100.0
                )
            };
            warnings.push(format!(
                "{what}: {} present; frond keeps 4 influences per vertex and merged the sets: {outcome}",
                extra.join(", ")
            ));
        }
    }
}
