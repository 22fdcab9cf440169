//! The crate's methods by name: parsing a `--method` name, configuring the method it names
//! with the run's options, the warnings for options it ignores, and the rule of `auto`, all
//! from [`crate::methods::REGISTRY`]. The types themselves (the method trait, its context and
//! output, the registry) are [`crate::method_api`]'s, re-exported here.

pub use crate::method_api::{
    BuildContext, ClusteringMethod, Foliage, IgnoredOptions, Method, MethodError, MethodName,
    MethodOptions, MethodOutput, PickContext, SkeletonOptions, SpectralOptions,
};
pub use crate::methods::METHOD_NAMES;
use crate::methods::{REGISTRY, auto};

impl MethodName {
    /// `auto`: the rule of [`auto_method`].
    pub const AUTO: MethodName = auto::NAME;

    /// Parses a name of [`METHOD_NAMES`].
    pub fn parse(s: &str) -> Option<MethodName> {
        REGISTRY.parse(s)
    }
}

impl Method {
    /// The method named `name`, with the given options for the spectral and skeleton methods
    /// (their description type comes from the name). Options of a method the name does not
    /// run are dropped; [`ignored_options`] says which, for a warning. An error for a name
    /// [`METHOD_NAMES`] does not list.
    pub fn new(
        name: MethodName,
        spectral: SpectralOptions,
        skeleton: SkeletonOptions,
    ) -> Result<Method, MethodError> {
        REGISTRY.configure(name, &MethodOptions { spectral, skeleton })
    }
}

/// Warnings for options given to a method that does not use them: spectral options
/// (`spectral_given`) act on spectral methods, and on `auto` only when it may pick one (with
/// spectral animation); skeleton options (`skeleton_given`) act on skeleton methods (`auto`
/// uses them for its nearest LOD, but they are not what `auto` is for).
pub fn ignored_options(
    name: MethodName,
    spectral_given: bool,
    skeleton_given: bool,
    spectral_animation: bool,
) -> Vec<IgnoredOptions> {
    REGISTRY.ignored_options(name, spectral_given, skeleton_given, spectral_animation)
}

/// The fixed rule of `--method auto` ([`crate::methods::auto`]) for the LOD of `lod`: the
/// method it picks and the reason written to the report.
pub fn auto_method(lod: &PickContext) -> (MethodName, &'static str) {
    let (pick, reason) = auto::rule(lod);
    let name = REGISTRY
        .parse(pick.method())
        .unwrap_or(MethodName::new(pick.method()));
    (name, reason)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral_k;
    use frond_skeleton::BoneDescriptionKind;
    use frond_spectral::description::SpectralKind;

    /// The LOD of rank `index` at `screen_height` px.
    fn lod(index: usize, spectral: bool, cards: bool, screen_height: f32) -> PickContext {
        PickContext {
            index,
            spectral_animation: spectral,
            card_foliage: cards,
            screen_height,
        }
    }

    #[test]
    fn method_names_round_trip() {
        let names: Vec<&str> = METHOD_NAMES.iter().map(|(n, _)| *n).collect();
        assert_eq!(
            names,
            [
                "auto",
                "per-bone",
                "static",
                "cards",
                "spectral",
                "spectral-naive",
                "spectral-dominating-axis",
                "spectral-axis-phase",
                "skeleton",
                "skeleton-axis-angle",
                "skeleton-rotation-spectral",
            ]
        );
        for (text, m) in METHOD_NAMES {
            assert_eq!(MethodName::parse(text), Some(*m));
            if *text != "spectral" && *text != "skeleton" {
                assert_eq!(m.name(), *text);
            }
        }
        assert_eq!(
            MethodName::parse("spectral").map(MethodName::name),
            Some("spectral-axis-phase")
        );
        assert_eq!(
            MethodName::parse("skeleton").map(MethodName::name),
            Some("skeleton-axis-angle")
        );
        assert_eq!(MethodName::parse("spectral-fourier"), None);
        assert_eq!(spectral_k(60.0), 6);
        assert_eq!(spectral_k(3.0), 1);
    }

    #[test]
    fn every_auto_pick_is_a_listed_method() {
        for pick in auto::AutoPick::ALL {
            assert!(MethodName::parse(pick.method()).is_some(), "{pick:?}");
        }
    }

    #[test]
    fn options_go_to_the_methods_that_use_them() {
        let spectral = SpectralOptions {
            clusters: Some(4),
            ..Default::default()
        };
        let skeleton_name = crate::methods::skeleton::name_of(BoneDescriptionKind::AxisAngle);
        let m = Method::new(skeleton_name, spectral.clone(), SkeletonOptions::default()).unwrap();
        assert_eq!(m.name(), skeleton_name);
        assert_eq!(m.pick(&lod(0, false, false, 600.0)).0.name(), skeleton_name);
        let w = ignored_options(skeleton_name, true, false, false);
        assert_eq!(w, [IgnoredOptions::Spectral(skeleton_name)]);
        assert!(w[0].to_string().contains("spectral options"), "{w:?}");
        assert!(ignored_options(MethodName::AUTO, true, false, true).is_empty());
        let m = Method::new(MethodName::AUTO, spectral, SkeletonOptions::default()).unwrap();
        assert_eq!(m.name(), MethodName::AUTO);
        let spectral_axis_phase = crate::methods::spectral::name_of(SpectralKind::AxisPhase);
        let (picked, _) = m.pick(&lod(1, true, false, 200.0));
        assert_eq!(picked.name(), spectral_axis_phase);
        let (picked, _) = m.pick(&lod(0, false, false, 600.0));
        assert_eq!(
            picked.name(),
            crate::methods::skeleton::name_of(crate::DEFAULT_SKELETON)
        );
        for (k, h) in [600.0, 200.0, 60.0].into_iter().enumerate() {
            let (picked, _) = m.pick(&lod(k, k == 1, true, h));
            assert_eq!(picked.name(), crate::methods::cards::NAME);
        }
        // The far end is an animated billboard cloud of FFT clusters, whatever the foliage.
        for (cards, spectral) in [(true, false), (false, false), (true, true)] {
            let (picked, why) = m.pick(&lod(3, spectral, cards, 20.0));
            assert_eq!(picked.name(), spectral_axis_phase, "{why}");
            assert!(why.contains("impostor"), "{why}");
        }
        assert!(
            Method::new(
                MethodName::new("nope"),
                Default::default(),
                Default::default()
            )
            .is_err()
        );
    }
}
