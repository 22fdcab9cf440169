//! `auto`: a fixed rule that picks a method per LOD, by its screen height, what the tree's
//! foliage is and how the files animate. An impostor-class LOD (the far end,
//! [`IMPOSTOR_HEIGHT`](crate::cost_budget::IMPOSTOR_HEIGHT) and below) gets `spectral-axis-phase`: the foliage clustered by its FFT
//! motion into at most the LOD's joint budget of clusters, each one baked billboard cloud with
//! one motion (spec animated-billboard-clouds §4.11–4.14). There a leaf card is a fraction of
//! a pixel, and a baked texel averages the many leaves a thinned card set would drop
//! (docs/experiments.md, "The far end"). Nearer, a tree whose foliage is single leaf cards
//! gets `cards` at every LOD: the
//! input's own cards, thinned to the LOD's triangle budget, on its leaf texture downscaled to
//! the LOD's texel density (docs/experiments.md has the coverage errors that chose it). Other
//! foliage (leaf clusters, where thinning would punch holes) gets the rule of the method
//! sweeps (docs/experiments.md §6–8): the nearest LOD `skeleton`, every farther one `static`,
//! or `spectral-axis-phase` when the files animate with spectral coefficients, whose
//! coefficient texture only spectral motion has. With spectral or VAT animation, card foliage
//! still gets `cards`: cards carry no motion of their own.
//!
//! The rule picks methods by the names `--method` takes, and finds them in the registry it is
//! configured from.

use std::sync::Arc;

use crate::cost_budget::is_impostor_class;
use crate::method_api::{
    ClusteringMethod, MethodChoice, MethodError, MethodName, MethodPlugin, OptionUse, PickContext,
};

/// `auto`'s name.
pub const NAME: MethodName = MethodName::new("auto");

/// `auto` as the registry lists it. It acts on the spectral options only when it may pick a
/// spectral method (spectral animation); it uses the skeleton options for its nearest LOD, but
/// they are not what `auto` is for.
pub const PLUGIN: MethodPlugin = MethodPlugin {
    names: &[("auto", NAME)],
    configure: |_, options, registry| {
        let picks = AutoPick::ALL.map(|pick| {
            let missing = || MethodError::RuleNeeds {
                rule: NAME,
                picks: pick.method().to_string(),
            };
            let name = registry.parse(pick.method()).ok_or_else(missing)?;
            Ok::<_, MethodError>(registry.configure(name, options)?.choice().clone())
        });
        let [cards, skeleton, spectral, static_cloud] = picks;
        Ok(Arc::new(AutoRule {
            picks: [cards?, skeleton?, spectral?, static_cloud?],
        }))
    },
    uses: |spectral_animation| OptionUse {
        spectral: spectral_animation,
        skeleton: false,
    },
};

/// What the rule picks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum AutoPick {
    /// `cards`: the input's cards, thinned.
    Cards,
    /// `skeleton`: skeleton simplification with the default bone description type.
    Skeleton,
    /// `spectral-axis-phase`: spectral clustering, motion as a few cosines per billboard.
    SpectralAxisPhase,
    /// `static`: one cloud, every billboard fitted to its triangles' motion.
    Static,
}

impl AutoPick {
    /// Every pick, in the order the configured rule keeps their methods.
    pub const ALL: [AutoPick; 4] = [
        AutoPick::Cards,
        AutoPick::Skeleton,
        AutoPick::SpectralAxisPhase,
        AutoPick::Static,
    ];

    /// The method picked, as `--method` takes it.
    pub fn method(self) -> &'static str {
        match self {
            AutoPick::Cards => "cards",
            AutoPick::Skeleton => "skeleton",
            AutoPick::SpectralAxisPhase => "spectral-axis-phase",
            AutoPick::Static => "static",
        }
    }
}

/// The rule for the LOD of `lod`: the pick, and the reason written to the report.
pub fn rule(lod: &PickContext) -> (AutoPick, &'static str) {
    if is_impostor_class(lod.screen_height) {
        (
            AutoPick::SpectralAxisPhase,
            "auto: impostor-class LOD -> spectral-axis-phase (the foliage clustered by its FFT \
             motion into the joint budget's clusters, one baked billboard cloud and one motion \
             each)",
        )
    } else if lod.card_foliage {
        (
            AutoPick::Cards,
            "auto: foliage of single leaf cards -> cards (the input's cards thinned to the \
             triangle budget, its leaf texture at the LOD's texel density: no atlas)",
        )
    } else if lod.index == 0 {
        (
            AutoPick::Skeleton,
            "auto: nearest LOD -> skeleton (per-bone clouds; sibling bones share a rotation only \
             where no leaf would move a pixel)",
        )
    } else if lod.spectral_animation {
        (
            AutoPick::SpectralAxisPhase,
            "auto: farther LOD with --animation spectral -> spectral-axis-phase (motion as a few \
             cosines per billboard)",
        )
    } else {
        (
            AutoPick::Static,
            "auto: farther LOD -> static (one cloud, fewest billboards, best colour at matched \
             billboard counts)",
        )
    }
}

/// The rule, with the methods it picks configured.
#[derive(Debug)]
struct AutoRule {
    /// The method of each pick, in [`AutoPick::ALL`] order.
    picks: [Arc<dyn MethodChoice>; 4],
}

impl MethodChoice for AutoRule {
    fn pick(&self, lod: &PickContext) -> (&dyn ClusteringMethod, &'static str) {
        let (pick, reason) = rule(lod);
        let k = AutoPick::ALL.iter().position(|p| *p == pick).unwrap_or(0);
        (self.picks[k].pick(lod).0, reason)
    }
}
