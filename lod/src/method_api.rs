//! What a clustering method is to the chain builder (spec animated-billboard-clouds §3
//! "per-bone", §4 spectral clustering SCA, §6 skeleton simplification SBCS; thesis §5.2.2 for
//! `static`): the trait a method implements, what one LOD's build reads and returns, the report
//! section a method writes, and the registry entry that names a method and makes it from the
//! run's options. Nothing here knows any particular method: the methods (`crate::methods`)
//! implement these types and the registry lists them.
//!
//! A method is a type carrying its own options that implements [`ClusteringMethod`]: given one
//! LOD's [`BuildContext`] (the tree, its sampled loop, the LOD's screen size and error budget,
//! the static cloud's parameters) it returns the LOD's foliage as a [`Foliage`] representation,
//! with its report section. A [`MethodPlugin`] lists the names `--method` takes for it and
//! configures it; a [`Registry`] is a list of plugins, from which names are parsed and
//! methods configured into a [`Method`], what a chain request carries.

use std::fmt;
use std::sync::{Arc, Mutex};

use frond_billboard::cloud::CloudParams;
use frond_render::Renderer;
use frond_scene::wood::WoodMesh;
use frond_scene::{Length, Sampled, Tree};
use frond_skeleton::BoneDescriptionKind;
use frond_spectral::description::SpectralKind;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::contract::LoopClock;
pub use crate::contract::{CardFoliage, Foliage};
use crate::error::LodError;
use crate::screen_budget::LodLevel;
use crate::section_value::{SectionError, SectionValue};

/// A method's name: what `--method` takes (in full: `spectral-axis-phase`, not its alias
/// `spectral`) and what the report's `method` field writes. Names are compared as text.
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct MethodName(&'static str);

impl MethodName {
    /// LOD0's "method": the input tree itself, rewritten (no method built it).
    pub const INPUT: MethodName = MethodName("input");

    /// The name written `name`.
    pub const fn new(name: &'static str) -> MethodName {
        MethodName(name)
    }

    /// The name as written.
    pub const fn name(self) -> &'static str {
        self.0
    }
}

impl fmt::Debug for MethodName {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "MethodName({:?})", self.0)
    }
}

impl fmt::Display for MethodName {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str(self.0)
    }
}

impl Serialize for MethodName {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(self.0)
    }
}

impl<'de> Deserialize<'de> for MethodName {
    /// Any name reads back (a report may name a method this build does not list): each
    /// distinct name is kept once for the process's life.
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<MethodName, D::Error> {
        let text = String::deserialize(d)?;
        Ok(MethodName(intern(text)))
    }
}

/// `text` as a `&'static str`, the same one for equal texts: names read from reports.
fn intern(text: String) -> &'static str {
    static NAMES: Mutex<Vec<&'static str>> = Mutex::new(Vec::new());
    let mut names = NAMES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(&known) = names.iter().find(|n| **n == text) {
        return known;
    }
    let leaked: &'static str = Box::leak(text.into_boxed_str());
    names.push(leaked);
    leaked
}

/// Wall times of a method's build of one LOD, seconds.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct BuildTimings {
    /// Placing the foliage in the pose its clouds are built in.
    pub reference_pose: f64,
    /// Searching the billboards' planes.
    pub plane_search: f64,
    /// Baking the atlas.
    pub bake: f64,
    /// Fitting the billboards' motion.
    pub motion_fit: f64,
}

/// Everything one LOD's build reads, shared by every method.
pub struct BuildContext<'a> {
    /// Renders the bake.
    pub renderer: &'a Renderer,
    /// The tree whose foliage is built.
    pub tree: &'a Tree,
    /// The tree's loop, sampled (foliage trajectories).
    pub sampled: &'a Sampled,
    /// The samples' clip, start and period.
    pub clock: &'a LoopClock,
    /// The LOD's screen height and what it may spend: pixel size, ε, texel density, wood error.
    pub level: &'a LodLevel,
    /// 0 for LOD1, the nearest billboard LOD.
    pub index: usize,
    /// Plane search and bake parameters of this LOD's static clouds (ε, texel density, seed).
    pub cloud: &'a CloudParams,
    /// The rest-pose bounding-box diagonal: sizes float tolerances and relative lengths.
    pub scale: f32,
    /// This LOD's seed (the run's seed plus the LOD index).
    pub seed: u64,
    /// Most billboards the LOD may have (its triangle budget less the wood's, halved): the
    /// plane search widens ε until its planes fit ([`crate::cloud_build`]).
    pub max_billboards: Option<usize>,
    /// Most foliage triangles the LOD may have (its triangle budget less the wood's).
    pub max_foliage_triangles: Option<usize>,
    /// Most alpha-tested area (world units²) the LOD's foliage may have: the previous LOD's
    /// (the monotone rule on overdraw). Card LODs grow their survivors within it.
    pub max_alpha_tested_area: Option<f64>,
    /// Most skin joints the LOD may have: spectral clustering gives the far end one cluster
    /// per joint but the wood's.
    pub max_joints: Option<usize>,
    /// Wood the LOD's billboards draw besides the foliage (rest pose): the far end's branches
    /// too thin to keep as triangles, baked as the covered fraction they add. Never moved or
    /// clustered: each triangle is drawn onto the billboard nearest it.
    pub baked_wood: Option<&'a WoodMesh>,
}

/// A method's own part of a LOD's report entry: an entry key (`spectral`, `skeleton`,
/// `cards`, ...) and what the method says there, kept as it serialises.
#[derive(Clone, Debug, PartialEq)]
pub struct MethodSection {
    /// The key of the LOD's report entry the section is written under.
    pub key: String,
    /// The section, as its type serialised it.
    pub value: SectionValue,
}

impl MethodSection {
    /// The section `value` under `key`.
    pub fn new<T: Serialize + ?Sized>(key: &str, value: &T) -> Result<MethodSection, SectionError> {
        Ok(MethodSection {
            key: key.to_string(),
            value: SectionValue::of(value)?,
        })
    }
}

/// One method's result for one LOD.
pub struct MethodOutput {
    /// The LOD's foliage.
    pub foliage: Foliage,
    /// How long the build's stages took.
    pub timings: BuildTimings,
    /// What the method reports of its own, if anything.
    pub section: Option<MethodSection>,
}

/// A way to build a tree's foliage for one LOD (cluster it into animated billboards, or thin
/// its cards).
pub trait ClusteringMethod: fmt::Debug + Send + Sync {
    /// The method's name in reports (with its description type: `spectral-axis-phase`).
    fn name(&self) -> MethodName;
    /// Builds the LOD's foliage within the context's budget.
    fn build(&self, ctx: &BuildContext) -> Result<MethodOutput, LodError>;
    /// Whether [`ClusteringMethod::build`] reads the sampled poses, trajectories or average
    /// pose ([`frond_scene::Sampled::positions`]); a chain whose methods do not samples the
    /// loop without them.
    fn needs_poses(&self) -> bool {
        true
    }
}

/// What the choice of a LOD's method may depend on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PickContext {
    /// 0 for LOD1, the nearest billboard LOD.
    pub index: usize,
    /// The files animate billboards with spectral coefficients.
    pub spectral_animation: bool,
    /// The tree's foliage is single leaf cards (`crate::methods::cards::is_card_foliage`).
    pub card_foliage: bool,
    /// The LOD's screen height, pixels: an impostor-class LOD
    /// ([`crate::cost_budget::IMPOSTOR_HEIGHT`]) gets the far end's method.
    pub screen_height: f32,
}

/// The reason a LOD's report gives for a method the run named (no rule picked it).
pub const GIVEN: &str = "given with --method";

/// What builds each LOD of a chain: a method itself, or a rule (`auto`) that picks one per LOD.
pub trait MethodChoice: fmt::Debug + Send + Sync {
    /// The method that builds the LOD of `lod`, and the reason the report gives.
    fn pick(&self, lod: &PickContext) -> (&dyn ClusteringMethod, &'static str);
}

impl<M: ClusteringMethod> MethodChoice for M {
    /// Every LOD: the method itself, as given.
    fn pick(&self, _: &PickContext) -> (&dyn ClusteringMethod, &'static str) {
        (self, GIVEN)
    }
}

/// Options of spectral clustering (SCA, spec §4.11–4.14).
#[derive(Clone, Debug, PartialEq)]
pub struct SpectralOptions {
    /// Description type (§4.4–4.8).
    pub kind: SpectralKind,
    /// Animation clusters per LOD (None: [`crate::spectral_k`] of the LOD's screen height, or
    /// at an impostor-class LOD its joint budget less one: [`SpectralOptions::params`]).
    pub clusters: Option<usize>,
    /// Animation zone size (None: [`crate::DEFAULT_ZONE_FRACTION`] of the diagonal or the
    /// LOD's ε, the larger).
    pub zone_size: Option<Length>,
    /// Bind billboards to their triangles' deepest shared bone (§4.12).
    pub shared_bone: bool,
}

impl Default for SpectralOptions {
    fn default() -> Self {
        SpectralOptions {
            kind: crate::DEFAULT_SPECTRAL,
            clusters: None,
            zone_size: None,
            shared_bone: true,
        }
    }
}

/// Options of skeleton simplification (SBCS, spec §6).
#[derive(Clone, Debug, PartialEq)]
pub struct SkeletonOptions {
    /// Bone description type (§6.2).
    pub kind: BoneDescriptionKind,
    /// Billboard clouds per LOD (None: as few as merges no eye can see at the LOD's size
    /// allow: at most a pixel of foliage motion, half a pixel off a branch).
    pub clouds: Option<usize>,
    /// The average-animation-bone improvement (§6.1, thesis §7.1.2).
    pub average_bone: bool,
}

impl Default for SkeletonOptions {
    fn default() -> Self {
        SkeletonOptions {
            kind: crate::DEFAULT_SKELETON,
            clouds: None,
            average_bone: false,
        }
    }
}

/// The options of a run that methods read: each method takes the group it knows (the
/// description type comes from the method's name).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MethodOptions {
    /// Options of the spectral methods.
    pub spectral: SpectralOptions,
    /// Options of the skeleton methods.
    pub skeleton: SkeletonOptions,
}

/// Which groups of [`MethodOptions`] a method acts on (warnings name the others as ignored).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OptionUse {
    /// It acts on [`MethodOptions::spectral`].
    pub spectral: bool,
    /// It acts on [`MethodOptions::skeleton`].
    pub skeleton: bool,
}

/// Why a method could not be named or configured.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum MethodError {
    /// No plugin of the registry answers to the name.
    #[error("unknown method '{0}'")]
    Unknown(String),
    /// A rule picks a method the registry does not list.
    #[error("method '{rule}' picks '{picks}', which is not among the methods")]
    RuleNeeds {
        /// The rule's name.
        rule: MethodName,
        /// The name it picks.
        picks: String,
    },
}

/// An option group given to a method that does not act on it: a warning, naming the method.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum IgnoredOptions {
    /// [`MethodOptions::spectral`] was given to a method that ignores it.
    #[error(
        "the spectral options (clusters, zone size, shared bone) act on spectral methods only; \
         method '{0}' ignores them"
    )]
    Spectral(MethodName),
    /// [`MethodOptions::skeleton`] was given to a method that ignores it.
    #[error(
        "the skeleton options (clouds, average bone) act on skeleton methods only; method \
         '{0}' ignores them"
    )]
    Skeleton(MethodName),
}

/// Makes the method a plugin's name stands for, with the run's options; `registry` is where a
/// rule (`auto`) finds the methods it picks.
pub type Configure =
    fn(MethodName, &MethodOptions, Registry<'_>) -> Result<Arc<dyn MethodChoice>, MethodError>;

/// One method as a registry lists it: the names `--method` takes for it and how to make it.
#[derive(Clone, Copy)]
pub struct MethodPlugin {
    /// The names it answers to, in the order they are listed, each with the method name it
    /// stands for: an alias (`spectral`) stands for a full name (`spectral-axis-phase`).
    pub names: &'static [(&'static str, MethodName)],
    /// Makes the method named so (one of `names`' full names).
    pub configure: Configure,
    /// Which option groups it acts on; the argument says whether the files animate with
    /// spectral coefficients (`auto` then may pick a spectral method).
    pub uses: fn(bool) -> OptionUse,
}

impl fmt::Debug for MethodPlugin {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.debug_struct("MethodPlugin")
            .field("names", &self.names)
            .finish_non_exhaustive()
    }
}

/// A plugin's [`MethodPlugin::uses`] for a method that acts on no option group.
pub fn uses_no_options(_spectral_animation: bool) -> OptionUse {
    OptionUse::default()
}

/// A list of method plugins: the names `--method` takes, in order, and the methods they make.
/// The crate's own is `crate::methods::REGISTRY`; a test or an application may list more.
#[derive(Clone, Copy, Debug)]
pub struct Registry<'a>(pub &'a [MethodPlugin]);

impl<'a> Registry<'a> {
    /// The registry of `plugins`.
    pub const fn new(plugins: &'a [MethodPlugin]) -> Registry<'a> {
        Registry(plugins)
    }

    /// How many names its plugins answer to.
    pub const fn name_count(&self) -> usize {
        let mut count = 0;
        let mut i = 0;
        while i < self.0.len() {
            count += self.0[i].names.len();
            i += 1;
        }
        count
    }

    /// Every name its plugins answer to, with the method each stands for, in order; `N` is
    /// [`Registry::name_count`] (an array, so that a registry's names can be a constant).
    pub const fn names_array<const N: usize>(&self) -> [(&'static str, MethodName); N] {
        let mut out = [("", MethodName::INPUT); N];
        let (mut i, mut k) = (0, 0);
        while i < self.0.len() {
            let names = self.0[i].names;
            let mut j = 0;
            while j < names.len() {
                out[k] = names[j];
                k += 1;
                j += 1;
            }
            i += 1;
        }
        out
    }

    /// Every name with the method it stands for, in order.
    pub fn names(&self) -> impl Iterator<Item = (&'static str, MethodName)> + 'a {
        self.0.iter().flat_map(|p| p.names.iter().copied())
    }

    /// The method written `text` (a full name or an alias).
    pub fn parse(&self, text: &str) -> Option<MethodName> {
        self.names().find(|(n, _)| *n == text).map(|(_, m)| m)
    }

    /// The plugin that makes `name`.
    pub fn plugin(&self, name: MethodName) -> Option<&'a MethodPlugin> {
        self.0
            .iter()
            .find(|p| p.names.iter().any(|(_, m)| *m == name))
    }

    /// Warnings for options given to method `name` that it does not act on
    /// ([`MethodPlugin::uses`]): `spectral_given`, `skeleton_given` say which groups were given,
    /// `spectral_animation` whether the files animate with spectral coefficients.
    pub fn ignored_options(
        &self,
        name: MethodName,
        spectral_given: bool,
        skeleton_given: bool,
        spectral_animation: bool,
    ) -> Vec<IgnoredOptions> {
        let uses = self
            .plugin(name)
            .map_or(OptionUse::default(), |p| (p.uses)(spectral_animation));
        let mut warnings = Vec::new();
        if spectral_given && !uses.spectral {
            warnings.push(IgnoredOptions::Spectral(name));
        }
        if skeleton_given && !uses.skeleton {
            warnings.push(IgnoredOptions::Skeleton(name));
        }
        warnings
    }

    /// The method `name` configured with `options`.
    pub fn configure(
        &self,
        name: MethodName,
        options: &MethodOptions,
    ) -> Result<Method, MethodError> {
        let plugin = self
            .plugin(name)
            .ok_or_else(|| MethodError::Unknown(name.to_string()))?;
        Ok(Method {
            name,
            choice: (plugin.configure)(name, options, *self)?,
        })
    }
}

/// A method as a run configured it: its name (`auto` for the rule) and what builds each LOD.
#[derive(Clone, Debug)]
pub struct Method {
    name: MethodName,
    choice: Arc<dyn MethodChoice>,
}

impl Method {
    /// The method `choice`, named `name`: what a [`MethodPlugin`] configures.
    pub fn of(name: MethodName, choice: Arc<dyn MethodChoice>) -> Method {
        Method { name, choice }
    }

    /// The name the method was asked by (`auto` for the rule).
    pub fn name(&self) -> MethodName {
        self.name
    }

    /// What builds each LOD.
    pub fn choice(&self) -> &Arc<dyn MethodChoice> {
        &self.choice
    }

    /// The method that builds the LOD of `lod` and why: itself, or what a rule picks.
    pub fn pick(&self, lod: &PickContext) -> (&dyn ClusteringMethod, &'static str) {
        self.choice.pick(lod)
    }
}
