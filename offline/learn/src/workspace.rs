//! LearnWorkspace (Sec. 4.1): the dilated safe workspace Ω+ of a location type from the
//! demonstrated configurations, compiled into the conservative field of
//! [`prf_shared::field`].
//!
//! 1. **Balls**: every sample of every instance is re-sampled linearly so that no sphere
//!    centre moves more than [`WorkspaceConfig::resample`] between configurations; each
//!    robot sphere (c_j, r_j) becomes the ball B(c_j, r_j + ε) in the location frame.
//!    Ω+ is their union.
//! 2. **Features**: every grid node within reach of a ball gets the ball deepest at it,
//!    argmin_k |v − c_k| − R_k over the balls thinned to [`WorkspaceConfig::feature_spacing`]
//!    (a subset of Ω+, so every value is an upper bound of the signed distance).
//! 3. **Far field**: nodes no ball reaches get the exact Euclidean distance transform
//!    ([`crate::edt`]) to the nearest node inside Ω+, an upper bound of their distance.
//! 4. **Encoding**: bricks far outside become uniform; feature balls are quantized
//!    conservatively (offset rounded, radius shrunk by the rounding error).
//! 5. **Certificates** ([`crate::certify`]): every demonstrated sphere that the encoded field
//!    does not certify with margin [`WorkspaceConfig::certify_margin`] gets its own ball as a
//!    certificate in the cells around it, so every demonstrated configuration, and every one
//!    whose spheres lie within the margin of it, has risk 0.

use crate::capsule::{self, Capsule};
use crate::certify::{self, Certified};
use crate::edt;
use crate::in_file::{Seen, Spheres, ordinal_of};
use crate::kb::{Record, RecordBytes};
use crate::learn::KbFile;
use nalgebra::Vector3;
use prf_shared::JointVector;
use prf_shared::field::{
    BRICK, BRICK_NODES, Field, FieldData, MM, NODE_BYTES, OFFSET_UNIT, UNIFORM,
};
use prf_shared::kinematics::Chain;
use prf_shared::robot::{MAX_SPHERES, RobotModel};
use prf_shared::se3::Pose;
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};
use std::collections::HashSet;
use std::ops::Range;

/// Settings of workspace learning.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WorkspaceConfig {
    /// Dilation ε = r_d − r, m.
    pub epsilon: f64,
    /// Node spacing h, m.
    pub voxel: f64,
    /// Maximum sphere-centre travel between re-sampled configurations, m.
    pub resample: f64,
    /// Spacing of the balls used for node features (a subset of the re-sampled ones), m.
    pub feature_spacing: f64,
    /// Nodes within this distance outside a ball get its exact feature, m.
    pub reach: f64,
    /// Bricks whose nodes are all at least this far outside Ω+ are stored as one value, m.
    pub far: f64,
    /// Demonstrated spheres must be certified with this margin (sdf + r ≤ −margin), m: a new
    /// program whose every sphere lies within it of a demonstrated position of the same
    /// robot sphere rates risk 0. Learning caps it ([`WorkspaceConfig::margin_for`]).
    pub certify_margin: f64,
}

impl Default for WorkspaceConfig {
    fn default() -> Self {
        WorkspaceConfig {
            epsilon: 0.02,
            voxel: 0.1,
            resample: 0.002,
            feature_spacing: 0.01,
            reach: 0.08,
            far: 0.16,
            certify_margin: REUSE_MARGIN,
        }
    }
}

impl WorkspaceConfig {
    /// The certification margin learning uses with dilation ε: [`Self::certify_margin`], at
    /// most what a demonstrated sphere's own certificate ball leaves (ε less its mm rounding,
    /// [`ROUNDING`]) and at least 1 mm.
    pub fn margin_for(&self, epsilon: f64) -> f64 {
        self.certify_margin.min(epsilon - ROUNDING).max(0.001)
    }
}

/// The default certification margin, m: every demonstrated sphere is certified for centres
/// within 8 mm of where it was, so a part placed some millimetres off still plans at risk 0.
/// It sizes the blob: with the 100 mm voxel, the example cell's workspaces take about twice
/// what 1 mm with a 50 mm voxel took.
pub const REUSE_MARGIN: f64 = 0.017;

/// What a sphere's own certificate ball can lose to its rounding at the sphere's centre, m:
/// the centre's rounding to the [`prf_shared::field::CERT_UNIT`] grid (up to √3/2 of half a
/// step) twice (the centre moves, and the radius shrinks by as much) and the radius rounded
/// down (a step), rounded up.
pub const ROUNDING: f64 = 0.0005;

/// A robot sphere at a demonstrated configuration, in the location frame: centre and radius
/// r_j (the ball of Ω+ around it has radius r_j + ε), and the piece of its path it lies on
/// (an index into [`Sweep::capsules`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SphereSample {
    pub centre: Vector3<f64>,
    pub radius: f64,
    pub capsule: u32,
}

/// A robot sphere of a swept configuration: its centre in the location frame and its index
/// in the robot model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathSphere {
    pub centre: Vector3<f64>,
    pub sphere: u8,
}

/// The demonstrated spheres of one location type, de-duplicated, and the feature balls
/// thinned from them (both in the order the spheres were added, so adding paths one by one
/// gives what adding them at once gives).
#[derive(Clone, Debug)]
pub struct Sweep {
    pub spheres: Spheres,
    /// The pieces of the demonstrated paths the spheres lie on ([`crate::capsule`]).
    pub capsules: Vec<Capsule>,
    /// The [`SeenKey`]s of `spheres`.
    seen: Seen,
    /// Feature-ball spacing, m ([`WorkspaceConfig::feature_spacing`]).
    feature_spacing: f64,
    /// The thinned spheres (centre, r_j): every sphere whose centre is not within the
    /// feature spacing of an already kept one of the same radius.
    features: Vec<(Vector3<f64>, f64)>,
    kept: FxHashSet<(i64, i64, i64, i64)>,
    /// The last field build's splat, continued by the next one.
    splat: Option<Splat>,
    /// The last field build's certificate decisions, continued by the next one.
    certified: Option<Certified>,
}

impl Default for Sweep {
    /// A sweep with the default feature spacing.
    fn default() -> Self {
        Sweep::new(WorkspaceConfig::default().feature_spacing)
    }
}

impl Sweep {
    /// An empty sweep thinning its feature balls to `feature_spacing` (m).
    pub fn new(feature_spacing: f64) -> Self {
        Sweep {
            spheres: Spheres::default(),
            capsules: Vec::new(),
            seen: Seen::default(),
            feature_spacing,
            features: Vec::new(),
            kept: FxHashSet::default(),
            splat: None,
            certified: None,
        }
    }

    /// The feature balls' spheres (centre, r_j), thinned to the feature spacing: the balls
    /// the field's nodes choose from once dilated by ε.
    pub fn features(&self) -> &[(Vector3<f64>, f64)] {
        &self.features
    }

    /// Adds the spheres of a configuration path (`arm` joint samples, arm base at
    /// `arm_base` in the location frame), re-sampled so no centre moves more than `step`.
    pub fn add_path(&mut self, model: &RobotModel, arm_base: &Pose, arm: &[[f64; 7]], step: f64) {
        let path = SweptPath::of(model, arm_base, arm, step);
        self.add_spheres(model, &[&path]);
    }

    /// The sweep as plain data, for the knowledge-base file ([`crate::kb`]).
    pub(crate) fn to_state(&self) -> crate::kb::SweepState<'static> {
        let v = |p: &Vector3<f64>| [p.x, p.y, p.z];
        crate::kb::SweepState {
            spheres: self.spheres.to_records(),
            capsules: RecordBytes::written(&[], &self.capsules),
            seen: self.seen.to_records(),
            feature_spacing: self.feature_spacing,
            features: self.features.iter().map(|(c, r)| (v(c), *r)).collect(),
            splat: self.splat_state(),
        }
    }

    /// Adds the spheres of `paths` ([`Sweep::add_spheres`]) after recovering the certificate
    /// decisions of the build that gave `field` from the spheres before them, when the sweep
    /// has none (it was read from a knowledge base, which does not keep them), so that the
    /// next build decides only what changed ([`Certified::recover`]). The recovery and the
    /// search for new spheres read the sweep at once, on two threads. Returns the indices of
    /// the new spheres across `paths` (each path's after those of the paths before it),
    /// ascending.
    pub(crate) fn grow(
        &mut self,
        model: &RobotModel,
        paths: &[&SweptPath],
        field: Option<&LearnedField>,
        cfg: &WorkspaceConfig,
    ) -> Vec<u32> {
        let recover = field.filter(|_| self.certified.is_none());
        let (certified, fresh) = rayon::join(
            || recover.and_then(|f| Certified::recover(f, self.spheres.len(), cfg)),
            || self.fresh(model, paths),
        );
        if recover.is_some() {
            self.certified = certified;
        }
        self.add_fresh(fresh)
    }

    /// The last field build's splat as plain data.
    pub(crate) fn splat_state(&self) -> Option<crate::kb::SplatState> {
        let v = |p: &Vector3<f64>| [p.x, p.y, p.z];
        self.splat.as_ref().map(|s| crate::kb::SplatState {
            origin: v(&s.key.0),
            dims: s.key.1,
            grid: [s.key.2, s.key.3, s.key.4],
            value: s.value.clone(),
            feature: s.feature.clone(),
            done: s.done,
        })
    }

    /// The splat [`Sweep::splat_state`] gave, as the last field build's. One that does not fit
    /// its grid or these feature balls is dropped (it is a cache: the next build splats
    /// afresh, to the same values).
    pub(crate) fn set_splat(&mut self, splat: Option<crate::kb::SplatState>) {
        let v = |p: [f64; 3]| Vector3::new(p[0], p[1], p[2]);
        let features = self.features.len();
        self.splat = splat
            .filter(|p| {
                let n = p.dims.iter().fold(1usize, |n, d| n.saturating_mul(*d));
                p.value.len() == n
                    && p.feature.len() == n
                    && p.done <= features
                    && p.feature
                        .iter()
                        .all(|f| *f == u32::MAX || (*f as usize) < p.done)
            })
            .map(|p| Splat {
                key: (v(p.origin), p.dims, p.grid[0], p.grid[1], p.grid[2]),
                value: p.value,
                feature: p.feature,
                done: p.done,
            });
    }

    /// Nodes of the grid a field build of this sweep would allocate with `cfg`, once the
    /// spheres `more` (centre, radius) are added too.
    pub(crate) fn grid_nodes(
        &self,
        more: impl Iterator<Item = (Vector3<f64>, f64)>,
        cfg: &WorkspaceConfig,
    ) -> usize {
        let balls = self.features.iter().copied().chain(more);
        let Some((lo, hi)) = bounds(balls.map(|(c, r)| (c, r + cfg.epsilon))) else {
            return 0;
        };
        let (_, dims) = grid_of(lo, hi, cfg);
        dims.iter().fold(1usize, |n, d| n.saturating_mul(*d))
    }

    /// The sweep [`Sweep::to_state`] gave ([`Sweep::set_splat`] for its splat), its spheres
    /// and keys left in `file` when `s` was read from it ([`crate::in_file`]).
    pub(crate) fn from_state(s: crate::kb::SweepState<'_>, file: Option<&KbFile>) -> Self {
        let v = |p: [f64; 3]| Vector3::new(p[0], p[1], p[2]);
        let mut sweep = Sweep {
            spheres: Spheres::of(&s.spheres, file),
            capsules: s.capsules.decoded(),
            seen: Seen::of(&s.seen, file),
            feature_spacing: s.feature_spacing,
            // Derived: one key per feature ball (a ball is kept iff its key is new).
            kept: s
                .features
                .iter()
                .map(|(c, r)| feature_key(&v(*c), *r, s.feature_spacing))
                .collect(),
            features: s.features.into_iter().map(|(c, r)| (v(c), r)).collect(),
            splat: None,
            // A cache the file does not keep: the next build decides every cell.
            certified: None,
        };
        sweep.set_splat(s.splat);
        sweep
    }

    /// Adds the spheres of `paths` not seen yet, in their order: a sphere is new when no
    /// earlier one (kept, or before it in `paths`) has its `SeenKey`. The paths' keys come
    /// sorted ([`SweptPath`]): they are merged with each other and with the kept ones in
    /// sequential passes, instead of a hash lookup per sphere (a cache miss each, 0.2 µs).
    pub fn add_spheres(&mut self, model: &RobotModel, paths: &[&SweptPath]) {
        let fresh = self.fresh(model, paths);
        self.add_fresh(fresh);
    }

    /// The spheres [`Sweep::add_spheres`] adds, in order, and their keys, sorted.
    fn fresh(&self, model: &RobotModel, paths: &[&SweptPath]) -> Fresh {
        let (mut starts, mut start) = (Vec::with_capacity(paths.len()), 0);
        for p in paths {
            starts.push(start);
            start += p.len() as u32;
        }
        // The keys below the sweep's middle one and the others, each half on a core.
        let mut fresh = match self.seen.middle() {
            Some(m) => {
                let (mut low, high) = rayon::join(
                    || self.fresh_in(paths, &starts, None, Some(m)),
                    || self.fresh_in(paths, &starts, Some(m), None),
                );
                low.extend(high);
                low
            }
            None => self.fresh_in(paths, &starts, None, None),
        };
        let keys: Vec<SeenKey> = fresh.iter().map(|e| e.0).collect();
        // Re-visited configurations (the reversal, repeated programs) add nothing new.
        fresh.sort_unstable_by_key(|e| e.1);
        let path_of = |i: u32| starts.partition_point(|s| *s <= i) - 1;
        // The pieces of each path's new spheres, on every core; a piece is kept when a new
        // sphere names it, in the order of the first such sphere.
        let mut touched: Vec<(usize, Vec<u32>)> = Vec::new();
        for &(_, i) in &fresh {
            let p = path_of(i);
            if touched.last().is_none_or(|t| t.0 != p) {
                touched.push((p, Vec::new()));
            }
            if let Some(t) = touched.last_mut() {
                t.1.push(i - starts[p]);
            }
        }
        let cut: Vec<(Vec<u32>, Vec<Capsule>)> = touched
            .par_iter()
            .map(|(p, new)| path_capsules(paths[*p], new))
            .collect();
        let mut kept: FxHashMap<(usize, u32), u32> = FxHashMap::default();
        let mut capsules = Vec::new();
        let mut spheres = Vec::with_capacity(fresh.len());
        let from = fresh.iter().map(|e| e.1).collect();
        let mut at = 0;
        for &(_, i) in &fresh {
            let p = path_of(i);
            let local = i - starts[p];
            let s = paths[p].sphere(local as usize);
            at += touched[at..].iter().position(|t| t.0 == p).unwrap_or(0);
            let (new, (of, pieces)) = (&touched[at].1, &cut[at]);
            let piece = of[new.partition_point(|n| *n < local)];
            let next = (self.capsules.len() + capsules.len()) as u32;
            let capsule = *kept.entry((p, piece)).or_insert_with(|| {
                capsules.push(pieces[piece as usize]);
                next
            });
            spheres.push(SphereSample {
                centre: s.centre,
                radius: model.spheres[s.sphere as usize].radius,
                capsule,
            });
        }
        Fresh {
            keys,
            spheres,
            capsules,
            from,
        }
    }

    /// [`Sweep::fresh`]'s new keys in `[from, to)`, ascending, with the index across `paths`
    /// (each starting at its `starts` entry) of the earliest sphere of each: the paths' sorted
    /// runs merged, the earliest of equal keys kept ([`merged`]), then those the sweep has
    /// seen dropped.
    fn fresh_in(
        &self,
        paths: &[&SweptPath],
        starts: &[u32],
        from: Option<SeenKey>,
        to: Option<SeenKey>,
    ) -> Vec<(SeenKey, u32)> {
        let runs = paths.iter().zip(starts).map(|(p, &start)| {
            let at = |bound: Option<SeenKey>, or: usize| bound.map_or(or, |b| p.keys.below(b));
            Run {
                keys: p.keys.run(at(from, 0)..at(to, p.keys.len())),
                start,
            }
        });
        self.seen.unseen(merged(runs.collect()), from).collect()
    }

    /// Adds what [`Sweep::fresh`] found: the keys, the spheres, and the feature balls they
    /// thin to. Returns the spheres' indices across the paths.
    fn add_fresh(&mut self, fresh: Fresh) -> Vec<u32> {
        self.seen.insert(&fresh.keys);
        self.capsules.extend(fresh.capsules);
        for s in &fresh.spheres {
            if self
                .kept
                .insert(feature_key(&s.centre, s.radius, self.feature_spacing))
            {
                self.features.push((s.centre, s.radius));
            }
        }
        self.spheres.extend(fresh.spheres);
        fresh.from
    }
}

/// New swept spheres of a sweep, in order, and their keys, sorted ([`Sweep::fresh`]).
struct Fresh {
    keys: Vec<SeenKey>,
    spheres: Vec<SphereSample>,
    /// The pieces the new spheres lie on, not yet in the sweep's.
    capsules: Vec<Capsule>,
    /// Each sphere's index across the paths it came from.
    from: Vec<u32>,
}

/// Per sphere `new` of `path` (indices, ascending), its piece among theirs
/// ([`capsule::pieces`] of each robot sphere's samples among them, in path order), and the
/// pieces. Only the spheres new to the sweep are cut: an addition keeps just those of its
/// paths, and replayed, they are cut alike.
fn path_capsules(path: &SweptPath, new: &[u32]) -> (Vec<u32>, Vec<Capsule>) {
    let mut chains: Vec<Vec<usize>> = vec![Vec::new(); u8::MAX as usize + 1];
    for (n, &i) in new.iter().enumerate() {
        chains[path.sphere(i as usize).sphere as usize].push(n);
    }
    let mut of = vec![0; new.len()];
    let mut capsules = Vec::new();
    for chain in chains.iter().filter(|c| !c.is_empty()) {
        let centres: Vec<Vector3<f64>> = chain
            .iter()
            .map(|&n| path.sphere(new[n] as usize).centre)
            .collect();
        let (pieces, more) = capsule::pieces(&centres);
        let base = capsules.len() as u32;
        for (&n, piece) in chain.iter().zip(pieces) {
            of[n] = base + piece;
        }
        capsules.extend(more);
    }
    (of, capsules)
}

/// The swept spheres of one instance ([`SweptPath::of`]) and, sorted, each of
/// their `SeenKey`s with the index of its first sphere: the de-duplication within the path,
/// done once with the demonstration's lessons rather than at each [`Sweep::add_spheres`].
#[derive(Clone, Debug, PartialEq)]
pub struct SweptPath {
    /// The spheres in order, as the knowledge base's records: an addition writes them as
    /// they are, without a copy in between.
    spheres: RecordBytes<'static, PathSphere>,
    keys: PathKeys,
}

impl SweptPath {
    /// The spheres of a configuration path (`arm` joint samples, arm base at `arm_base` in
    /// the location frame), re-sampled so no centre moves more than `step`, in order. A
    /// sphere whose key is that of the same robot sphere one configuration earlier (near the
    /// base, or at rest; 24 % of each of d063's two arm lessons) is left out: it can never be
    /// new.
    pub fn of(model: &RobotModel, arm_base: &Pose, arm: &[[f64; 7]], step: f64) -> Self {
        let n = model.spheres.len();
        let chain = Chain::new(model);
        let centres = |q: &JointVector| {
            let mut c = [Vector3::zeros(); MAX_SPHERES];
            chain.kinematics(model, q).sphere_centres(model, &mut c);
            c
        };
        let mut spheres = Vec::with_capacity(arm.len() * n * PathSphere::SIZE);
        let mut keys = RawKeys::with_capacity(arm.len() * n);
        let mut last = LastKeys::default();
        let mut put = |c: &[Vector3<f64>]| {
            for (j, c) in c.iter().enumerate() {
                let s = PathSphere {
                    centre: arm_base.transform_point(&(*c).into()).coords,
                    sphere: j as u8,
                };
                let key = seen_key(&s);
                if last.moved(&s, key) {
                    keys.push(key);
                    let mut record = [0; PathSphere::SIZE];
                    s.put(&mut record);
                    spheres.extend_from_slice(&record);
                }
            }
        };
        let mut prev: Option<(JointVector, [Vector3<f64>; MAX_SPHERES])> = None;
        for q in arm {
            let q = JointVector::from(*q);
            let c1 = centres(&q);
            match prev {
                None => put(&c1[..n]),
                Some((q0, c0)) => {
                    let travel = (0..n).map(|j| (c1[j] - c0[j]).norm()).fold(0.0, f64::max);
                    let parts = (travel / step).ceil().max(1.0) as usize;
                    for s in 1..=parts {
                        let t = s as f64 / parts as f64;
                        let c = if s == parts {
                            c1
                        } else {
                            centres(&q0.lerp(&q, t))
                        };
                        put(&c[..n]);
                    }
                }
            }
            prev = Some((q, c1));
        }
        let spheres = RecordBytes::new(spheres.into());
        SweptPath {
            keys: keys.sorted(&spheres),
            spheres,
        }
    }

    /// The path of `spheres` as stored ([`SweptPath::of`]'s, or from before it left out
    /// repeated spheres: those are left out of the keys here).
    pub fn new(spheres: &[PathSphere]) -> Self {
        Self::of_records(RecordBytes::written(&[], spheres))
    }

    /// The path of its spheres at `indices`, in their order.
    pub(crate) fn only(&self, indices: &[u32]) -> Self {
        let spheres: Vec<PathSphere> = indices.iter().map(|&i| self.sphere(i as usize)).collect();
        Self::new(&spheres)
    }

    /// [`SweptPath::new`] of the spheres as the knowledge base's records.
    pub(crate) fn of_records(spheres: RecordBytes<'static, PathSphere>) -> Self {
        let mut last = LastKeys::default();
        let mut keys: Vec<(SeenKey, u32)> = Vec::with_capacity(spheres.len());
        for i in 0..spheres.len() {
            let s = spheres.get(i);
            let key = seen_key(&s);
            if last.moved(&s, key) {
                keys.push((key, i as u32));
            }
        }
        SweptPath {
            spheres,
            keys: PathKeys::of(keys),
        }
    }

    /// Number of spheres.
    pub fn len(&self) -> usize {
        self.spheres.len()
    }

    /// Whether the path holds no sphere.
    pub fn is_empty(&self) -> bool {
        self.spheres.len() == 0
    }

    /// Sphere `i` (< [`SweptPath::len`]).
    pub fn sphere(&self, i: usize) -> PathSphere {
        self.spheres.get(i)
    }

    /// The spheres in order.
    pub fn spheres(&self) -> impl Iterator<Item = PathSphere> + '_ {
        (0..self.len()).map(|i| self.sphere(i))
    }

    /// The spheres as the knowledge base's records.
    pub(crate) fn records(&self) -> &RecordBytes<'static, PathSphere> {
        &self.spheres
    }
}

/// A run of sorted keys: ascending, without repeats, each key with the index of its
/// sphere, the indices offset by `start` (distinct across the runs merged together).
struct Run<'a> {
    keys: RunKeys<'a>,
    start: u32,
}

/// The keys of a [`Run`]: a path's packed ones ([`PathKeys`]), or pairs.
enum RunKeys<'a> {
    Packed(&'a Packing, &'a [u64]),
    Pairs(std::borrow::Cow<'a, [(SeenKey, u32)]>),
}

impl RunKeys<'_> {
    /// Entry `i`, if there is one.
    #[inline]
    fn get(&self, i: usize) -> Option<(SeenKey, u32)> {
        match self {
            RunKeys::Packed(p, words) => words.get(i).map(|w| p.unpack(*w)),
            RunKeys::Pairs(keys) => keys.get(i).copied(),
        }
    }
}

/// The runs merged into one, keeping of equal keys the entry of least index: what merging by
/// (key, index) and keeping the first of each key gives. Two runs are merged as they are
/// read ([`MergeTwo`]); more are first merged in pairs, into arrays, down to two.
fn merged(mut runs: Vec<Run<'_>>) -> MergeTwo<'_> {
    while runs.len() > 2 {
        let mut next = Vec::with_capacity(runs.len().div_ceil(2));
        let mut pairs = runs.into_iter();
        while let Some(a) = pairs.next() {
            next.push(match pairs.next() {
                Some(b) => Run {
                    keys: RunKeys::Pairs(MergeTwo::new(a, b).collect::<Vec<_>>().into()),
                    start: 0,
                },
                None => a,
            });
        }
        runs = next;
    }
    let mut runs = runs.into_iter();
    let empty = || Run {
        keys: RunKeys::Pairs((&[][..]).into()),
        start: 0,
    };
    MergeTwo::new(
        runs.next().unwrap_or_else(empty),
        runs.next().unwrap_or_else(empty),
    )
}

/// Two runs merged as they are read ([`merged`]). Which run's entry comes next is a coin toss
/// that a processor mispredicts, so the choice is made without a branch: d063's two arm
/// lessons merged and filtered against each half of the Table's sweep take 1.5–2.0 ms,
/// against 2.1–2.7 ms with itertools' k-way merge (temporary timers).
struct MergeTwo<'a> {
    a: Run<'a>,
    b: Run<'a>,
    i: usize,
    j: usize,
}

impl<'a> MergeTwo<'a> {
    fn new(a: Run<'a>, b: Run<'a>) -> Self {
        MergeTwo { a, b, i: 0, j: 0 }
    }
}

impl Iterator for MergeTwo<'_> {
    type Item = (SeenKey, u32);

    fn next(&mut self) -> Option<(SeenKey, u32)> {
        let (a, b) = (self.a.keys.get(self.i), self.b.keys.get(self.j));
        let x = a.map(|(k, i)| (k, i + self.a.start));
        let y = b.map(|(k, i)| (k, i + self.b.start));
        match (x, y) {
            (Some(x), Some(y)) => {
                let (kx, ky) = (ordinal_of(&x.0), ordinal_of(&y.0));
                let x_first = (kx < ky) | ((kx == ky) & (x.1 < y.1));
                self.i += usize::from(kx <= ky);
                self.j += usize::from(ky <= kx);
                Some([y, x][usize::from(x_first)])
            }
            (Some(x), None) => {
                self.i += 1;
                Some(x)
            }
            (None, y) => {
                self.j += usize::from(y.is_some());
                y
            }
        }
    }
}

/// The last key of each robot sphere along a path.
struct LastKeys([Option<SeenKey>; 256]);

impl Default for LastKeys {
    fn default() -> Self {
        LastKeys([None; 256])
    }
}

impl LastKeys {
    /// Whether `key` of `s` differs from its robot sphere's last one, which it becomes: a
    /// sphere that repeats it (near the base, or at rest) can never be new.
    fn moved(&mut self, s: &PathSphere, key: SeenKey) -> bool {
        self.0[usize::from(s.sphere)].replace(key) != Some(key)
    }
}

/// A path's keys, sorted, each once with the index of its earliest sphere. Where the path's
/// extent allows ([`Packing`]), key and index are kept and sorted as one `u64`: for d063's two
/// arm lessons 26.4 M instructions with the packing, against 43.2 M sorting the pairs
/// (`valgrind --tool=callgrind` of `prf learn --add`), and 8 bytes a key where a pair takes 20.
#[derive(Clone, Debug, PartialEq)]
enum PathKeys {
    Packed(Packing, Vec<u64>),
    Pairs(Vec<(SeenKey, u32)>),
}

impl PathKeys {
    /// `keys` (each with the index of its sphere) sorted by key, the earliest of equal keys
    /// kept.
    fn of(mut keys: Vec<(SeenKey, u32)>) -> Self {
        match Packing::of(&keys) {
            Some(p) => {
                let words = keys.iter().map(|e| p.pack(e)).collect();
                PathKeys::packed(p, words)
            }
            None => {
                keys.sort_unstable();
                keys.dedup_by_key(|e| e.0);
                PathKeys::Pairs(keys)
            }
        }
    }

    /// `words`, packed by `p`, sorted and de-duplicated by key.
    fn packed(p: Packing, mut words: Vec<u64>) -> Self {
        words.sort_unstable();
        words.dedup_by_key(|w| p.key_of(*w));
        PathKeys::Packed(p, words)
    }

    fn len(&self) -> usize {
        match self {
            PathKeys::Packed(_, words) => words.len(),
            PathKeys::Pairs(keys) => keys.len(),
        }
    }

    /// The number of keys below `bound`.
    fn below(&self, bound: SeenKey) -> usize {
        match self {
            PathKeys::Packed(p, words) => words.partition_point(|w| p.unpack(*w).0 < bound),
            PathKeys::Pairs(keys) => keys.partition_point(|e| e.0 < bound),
        }
    }

    /// The keys in `range` as a run.
    fn run(&self, range: Range<usize>) -> RunKeys<'_> {
        match self {
            PathKeys::Packed(p, words) => RunKeys::Packed(p, &words[range]),
            PathKeys::Pairs(keys) => RunKeys::Pairs(keys[range].into()),
        }
    }

    /// The keys with their indices, in order.
    #[cfg(test)]
    fn to_vec(&self) -> Vec<(SeenKey, u32)> {
        let run = self.run(0..self.len());
        (0..self.len()).filter_map(|i| run.get(i)).collect()
    }
}

/// Bits of each coordinate's offset in a [`RawKeys`] word: ±26 m from the first key.
const RAW_BITS: u32 = 18;

/// A path's keys as [`SweptPath::of`] finds them, one per sphere kept, in order (the index is
/// the position): each in a `u64`, its coordinates as offsets from the first key's (in
/// [`RAW_BITS`] bits, offset by half their range) above its robot sphere; with their extent,
/// for the [`Packing`] they are sorted in. 8 bytes a key, where the pairs took 20 (a path's
/// keys were a third of the page faults of `prf learn --add`).
struct RawKeys {
    first: Option<[i32; 3]>,
    words: Vec<u64>,
    least: [i32; 3],
    most: [i32; 3],
    sphere: u8,
    /// A key too far from the first for its word: the keys are taken from the spheres.
    wide: bool,
}

impl RawKeys {
    fn with_capacity(n: usize) -> Self {
        RawKeys {
            first: None,
            words: Vec::with_capacity(n),
            least: [i32::MAX; 3],
            most: [i32::MIN; 3],
            sphere: 0,
            wide: false,
        }
    }

    /// Adds the key of the next sphere kept.
    #[inline]
    fn push(&mut self, (x, y, z, sphere): SeenKey) {
        let first = *self.first.get_or_insert([x, y, z]);
        let mut word = 0;
        for (c, v) in [x, y, z].into_iter().enumerate() {
            self.least[c] = self.least[c].min(v);
            self.most[c] = self.most[c].max(v);
            let offset = i64::from(v) - i64::from(first[c]) + (1 << (RAW_BITS - 1));
            self.wide |= !(0..1 << RAW_BITS).contains(&offset);
            word = word << RAW_BITS | (offset as u64 & ((1 << RAW_BITS) - 1));
        }
        self.sphere = self.sphere.max(sphere);
        self.words.push(word << 8 | u64::from(sphere));
    }

    /// The key in `word`.
    fn key(&self, word: u64) -> SeenKey {
        let first = self.first.unwrap_or_default();
        let coordinate = |c: usize| {
            let shift = 8 + RAW_BITS * (2 - c as u32);
            let offset = (word >> shift & ((1 << RAW_BITS) - 1)) as i64;
            (i64::from(first[c]) + offset - (1 << (RAW_BITS - 1))) as i32
        };
        (coordinate(0), coordinate(1), coordinate(2), word as u8)
    }

    /// The keys sorted ([`PathKeys`]), repacked in place with their indices where the
    /// extent allows; else as pairs, the keys taken again from `spheres`, the path's spheres.
    fn sorted(mut self, spheres: &RecordBytes<'_, PathSphere>) -> PathKeys {
        let last = self.words.len().saturating_sub(1) as u32;
        let packing = Packing::fitting(self.least, self.most, self.sphere, last);
        match packing.filter(|_| !self.wide && !self.words.is_empty()) {
            Some(p) => {
                let mut words = std::mem::take(&mut self.words);
                for (i, w) in words.iter_mut().enumerate() {
                    *w = p.pack(&(self.key(*w), i as u32));
                }
                PathKeys::packed(p, words)
            }
            None => PathKeys::of(
                (0..spheres.len())
                    .map(|i| (seen_key(&spheres.get(i)), i as u32))
                    .collect(),
            ),
        }
    }
}

/// An order-preserving map of a path's keys, each with its sphere's index, into one `u64`:
/// the offsets of the coordinates from the path's least, the robot sphere and the index, in
/// that order, each in as many bits as the path needs (a lesson reaching 1.5 m along each
/// axis with 45,000 spheres needs 61).
#[derive(Clone, Debug, PartialEq)]
struct Packing {
    least: [i32; 3],
    /// Bit widths of x, y, z, the robot sphere and the index.
    width: [u32; 5],
    /// Where each field starts, from the lowest bit, and its mask (derived from `width`: a
    /// merge unpacks two keys per key it gives).
    shift: [u32; 5],
    mask: [u64; 5],
}

impl Packing {
    /// The packing of `keys`, or None when they need more than 64 bits.
    fn of(keys: &[(SeenKey, u32)]) -> Option<Self> {
        let (mut least, mut most) = ([i32::MAX; 3], [i32::MIN; 3]);
        let (mut sphere, mut index) = (0, 0);
        for ((x, y, z, s), i) in keys {
            for (c, v) in [*x, *y, *z].into_iter().enumerate() {
                least[c] = least[c].min(v);
                most[c] = most[c].max(v);
            }
            (sphere, index) = (sphere.max(*s), index.max(*i));
        }
        Self::fitting(least, most, sphere, index).filter(|_| !keys.is_empty())
    }

    /// The packing of keys within `least..=most`, robot spheres up to `sphere` and indices
    /// up to `index`, or None when they need more than 64 bits.
    fn fitting(least: [i32; 3], most: [i32; 3], sphere: u8, index: u32) -> Option<Self> {
        let bits = |v: u64| u64::BITS - v.leading_zeros();
        let extent = |c: usize| (i64::from(most[c]) - i64::from(least[c])).max(0) as u64;
        let width = [
            bits(extent(0)),
            bits(extent(1)),
            bits(extent(2)),
            bits(u64::from(sphere)),
            bits(u64::from(index)),
        ];
        let w = &width;
        let shift = [
            w[1] + w[2] + w[3] + w[4],
            w[2] + w[3] + w[4],
            w[3] + w[4],
            w[4],
            0,
        ];
        let mask = width.map(|b| u64::MAX.checked_shr(u64::BITS - b).unwrap_or(0));
        (width.iter().sum::<u32>() <= u64::BITS).then_some(Packing {
            least,
            width,
            shift,
            mask,
        })
    }

    /// `(key, index)` packed: ordered as the pairs are.
    fn pack(&self, (key, index): &(SeenKey, u32)) -> u64 {
        let offset = |v: i32, c: usize| (i64::from(v) - i64::from(self.least[c])) as u64;
        let fields = [
            offset(key.0, 0),
            offset(key.1, 1),
            offset(key.2, 2),
            u64::from(key.3),
            u64::from(*index),
        ];
        fields
            .iter()
            .zip(self.shift)
            .fold(0, |w, (f, s)| w | f.checked_shl(s).unwrap_or(0))
    }

    /// The key part of a packed pair.
    fn key_of(&self, w: u64) -> u64 {
        w.checked_shr(self.width[4]).unwrap_or(0)
    }

    /// The pair [`Packing::pack`] packed into `w`.
    #[inline]
    fn unpack(&self, w: u64) -> (SeenKey, u32) {
        // A field that starts at bit 64 has no bits: its mask is 0.
        let field = |f: usize| (w >> (self.shift[f] & (u64::BITS - 1))) & self.mask[f];
        let coordinate = |c: usize| (i64::from(self.least[c]) + field(c) as i64) as i32;
        (
            (coordinate(0), coordinate(1), coordinate(2), field(3) as u8),
            field(4) as u32,
        )
    }
}

/// The de-duplication key of a swept sphere: its centre on a 0.2 mm grid and its index.
pub(crate) type SeenKey = (i32, i32, i32, u8);

/// [`SeenKey`] of `s`.
fn seen_key(s: &PathSphere) -> SeenKey {
    let k = |v: f64| prf_shared::float::round_i32(v / 2e-4);
    (k(s.centre.x), k(s.centre.y), k(s.centre.z), s.sphere)
}

/// The thinning key of a feature ball: its centre on the feature-spacing grid and its radius
/// in 0.1 mm.
fn feature_key(p: &Vector3<f64>, radius: f64, spacing: f64) -> (i64, i64, i64, i64) {
    let k = |v: f64| (v / spacing).round() as i64;
    (k(p.x), k(p.y), k(p.z), (radius * 1e4) as i64)
}

/// The encoded field of one workspace and figures about it.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LearnedField {
    pub origin: [f32; 3],
    pub voxel: f32,
    pub dims: [u16; 3],
    pub bricks: Vec<u8>,
    pub nodes: Vec<u8>,
    pub certificates: Vec<u8>,
    pub capsules: Vec<u8>,
    /// Demonstrated spheres (after de-duplication) and feature balls used.
    pub spheres: usize,
    pub feature_balls: usize,
    /// Certificates left out because the field needed more than
    /// [`MAX_CAPSULES`](prf_shared::field::MAX_CAPSULES) capsules
    /// (the field stays conservative; the spheres they named rate a risk).
    pub uncertified: usize,
}

impl LearnedField {
    pub fn data(&self) -> FieldData<'_> {
        FieldData {
            origin: self.origin,
            voxel: self.voxel,
            dims: self.dims,
            bricks: &self.bricks,
            nodes: &self.nodes,
            certificates: &self.certificates,
            capsules: &self.capsules,
        }
    }

    /// The field view (valid by construction).
    pub fn field(&self) -> Field<'_> {
        Field::new(&self.data()).expect("a learned field is valid")
    }

    /// Bytes of the arrays.
    pub fn bytes(&self) -> usize {
        self.bricks.len() + self.nodes.len() + self.certificates.len() + self.capsules.len()
    }
}

/// The grid of a field: the feature balls' box plus a margin ([`WorkspaceConfig::far`] and a
/// node), widened outward to multiples of [`ANCHOR`] nodes from the frame's origin, so that a
/// growing sweep keeps its grid (and its splatted features) until it crosses a multiple.
/// Returns the first node's position and the node counts (whole bricks).
fn grid(balls: &[(Vector3<f64>, f64)], cfg: &WorkspaceConfig) -> (Vector3<f64>, [usize; 3]) {
    let (lo, hi) = bounds(balls.iter().copied())
        .unwrap_or((Vector3::repeat(f64::MAX), Vector3::repeat(f64::MIN)));
    grid_of(lo, hi, cfg)
}

/// The box of the balls (centre, radius), or None when there are none.
fn bounds(
    balls: impl Iterator<Item = (Vector3<f64>, f64)>,
) -> Option<(Vector3<f64>, Vector3<f64>)> {
    balls.fold(None, |b, (c, r)| {
        let (lo, hi) = (c - Vector3::repeat(r), c + Vector3::repeat(r));
        Some(b.map_or((lo, hi), |(l, h): (Vector3<f64>, Vector3<f64>)| {
            (l.inf(&lo), h.sup(&hi))
        }))
    })
}

/// [`grid`] of the balls' box `lo`..`hi`.
fn grid_of(
    lo: Vector3<f64>,
    hi: Vector3<f64>,
    cfg: &WorkspaceConfig,
) -> (Vector3<f64>, [usize; 3]) {
    let h = cfg.voxel as f32 as f64;
    let margin = cfg.far + h;
    let step = ANCHOR as f64 * h;
    let first = (lo - Vector3::repeat(margin)).map(|v| (v / step).floor());
    let last = (hi + Vector3::repeat(margin)).map(|v| (v / step).ceil());
    let lo = first.map(|k| (k * step) as f32 as f64);
    // Saturating: a hostile knowledge base's extents must not overflow (its grid is then
    // refused by size).
    let dims = core::array::from_fn(|a| {
        let n = ((last[a] - first[a]) as usize)
            .saturating_mul(ANCHOR)
            .saturating_add(1);
        n.div_ceil(BRICK).saturating_mul(BRICK)
    });
    (lo, dims)
}

/// Field grids start and end on multiples of this many nodes.
pub const ANCHOR: usize = 4;

/// The splatted features of the last field build of a sweep: per node the value of the
/// deepest feature ball and its index, for the first `done` balls, on the grid `key`.
#[derive(Clone, Debug)]
struct Splat {
    key: (Vector3<f64>, [usize; 3], f64, f64, f64),
    value: Vec<f64>,
    feature: Vec<u32>,
    done: usize,
}

/// Builds the field of Ω+ from the demonstrated spheres (steps 2–5 of the module doc).
pub fn build_field(sweep: &mut Sweep, cfg: &WorkspaceConfig) -> Option<LearnedField> {
    if sweep.spheres.is_empty() {
        return None;
    }
    // Node positions as the runtime computes them (f32 origin and spacing in the blob).
    let h = cfg.voxel as f32 as f64;
    let eps = cfg.epsilon;
    // Feature balls: the sweep's thinned spheres, dilated by ε.
    debug_assert_eq!(sweep.feature_spacing, cfg.feature_spacing);
    let balls: Vec<(Vector3<f64>, f64)> =
        sweep.features.iter().map(|(c, r)| (*c, r + eps)).collect();
    let (lo, dims) = grid(&balls, cfg);
    let [_, ny, nz] = dims;
    let idx = |i: usize, j: usize, k: usize| (i * ny + j) * nz + k;
    let pos = |i: usize, j: usize, k: usize| lo + Vector3::new(i as f64, j as f64, k as f64) * h;
    // Step 2: features by splatting, continuing the last build's when the grid is the same.
    let key = (lo, dims, eps, cfg.reach, h);
    let mut splat = match sweep.splat.take() {
        Some(s) if s.key == key && s.done <= balls.len() => s,
        _ => Splat {
            key,
            value: vec![f64::INFINITY; dims.iter().product()],
            feature: vec![u32::MAX; dims.iter().product()],
            done: 0,
        },
    };
    for (b, (c, r)) in balls.iter().enumerate().skip(splat.done) {
        let reach = r + cfg.reach;
        let from = |a: usize| (((c[a] - reach - lo[a]) / h).floor().max(0.0)) as usize;
        let to = |a: usize| ((((c[a] + reach - lo[a]) / h).ceil()) as usize).min(dims[a] - 1);
        for i in from(0)..=to(0) {
            let dx = pos(i, 0, 0).x - c.x;
            for j in from(1)..=to(1) {
                let dy = pos(0, j, 0).y - c.y;
                let dxy = dx * dx + dy * dy;
                let row = idx(i, j, 0);
                for k in from(2)..=to(2) {
                    let dz = pos(0, 0, k).z - c.z;
                    let d = (dxy + dz * dz).sqrt() - r;
                    let n = row + k;
                    if d < splat.value[n] {
                        splat.value[n] = d;
                        splat.feature[n] = b as u32;
                    }
                }
            }
        }
    }
    splat.done = balls.len();
    let mut value = splat.value.clone();
    let feature = splat.feature.clone();
    sweep.splat = Some(splat);
    // Step 3: far field from the EDT to the nodes inside Ω+.
    let mut sq: Vec<f64> = value
        .iter()
        .map(|&v| if v <= 0.0 { 0.0 } else { edt::FAR })
        .collect();
    edt::transform_3d(&mut sq, dims);
    for (v, s) in value.iter_mut().zip(&sq) {
        if v.is_infinite() {
            *v = if *s >= edt::FAR {
                f64::MAX
            } else {
                s.sqrt() * h
            };
        }
    }
    // Step 4: encoding.
    let bdims = dims.map(|n| n / BRICK);
    let mut bricks = Vec::with_capacity(2 * bdims.iter().product::<usize>());
    let mut nodes = Vec::new();
    let mut used = HashSet::new();
    let max_mm = (UNIFORM - 1) as f64;
    for bi in 0..bdims[0] {
        for bj in 0..bdims[1] {
            for bk in 0..bdims[2] {
                let brick_nodes = || {
                    (0..BRICK_NODES).map(move |l| {
                        let (i, j, k) = (l / (BRICK * BRICK), (l / BRICK) % BRICK, l % BRICK);
                        (bi * BRICK + i, bj * BRICK + j, bk * BRICK + k)
                    })
                };
                let min_value = brick_nodes()
                    .map(|(i, j, k)| value[idx(i, j, k)])
                    .fold(f64::INFINITY, f64::min);
                if min_value >= cfg.far {
                    let max_value = brick_nodes()
                        .map(|(i, j, k)| value[idx(i, j, k)])
                        .fold(0.0, f64::max);
                    let mm = (max_value / MM).ceil().min(max_mm);
                    bricks.extend_from_slice(&(UNIFORM + mm as u16).to_le_bytes());
                    continue;
                }
                let index = nodes.len() / (BRICK_NODES * NODE_BYTES);
                bricks.extend_from_slice(&(index as u16).to_le_bytes());
                for (i, j, k) in brick_nodes() {
                    let n = idx(i, j, k);
                    nodes.extend_from_slice(&encode_node(
                        &pos(i, j, k),
                        value[n],
                        (feature[n] != u32::MAX).then(|| balls[feature[n] as usize]),
                    ));
                    if feature[n] != u32::MAX {
                        used.insert(feature[n]);
                    }
                }
            }
        }
    }
    let mut learned = LearnedField {
        origin: [lo.x as f32, lo.y as f32, lo.z as f32],
        voxel: h as f32,
        dims: dims.map(|n| n as u16),
        bricks,
        nodes,
        certificates: Vec::new(),
        capsules: Vec::new(),
        spheres: sweep.spheres.len(),
        feature_balls: used.len(),
        uncertified: 0,
    };
    let (records, certified) = certify::certificates(
        &learned,
        &sweep.spheres,
        &sweep.capsules,
        sweep.certified.take(),
        cfg,
    );
    (learned.certificates, learned.capsules, learned.uncertified) = records;
    sweep.certified = Some(certified);
    Some(learned)
}

/// A node: its feature ball quantized conservatively when it exists and its centre is within
/// the offset range; otherwise the scalar bound rounded up.
fn encode_node(v: &Vector3<f64>, value: f64, ball: Option<(Vector3<f64>, f64)>) -> [u8; 4] {
    if let Some((c, r)) = ball {
        let off = (c - v) / OFFSET_UNIT;
        if off.iter().all(|o| o.abs() <= 127.0) {
            let q = off.map(|o| o.round());
            let err = ((q - off) * OFFSET_UNIT).norm();
            let r_mm = ((r - err) / MM).floor();
            if (1.0..=255.0).contains(&r_mm) {
                return [
                    q.x as i8 as u8,
                    q.y as i8 as u8,
                    q.z as i8 as u8,
                    r_mm as u8,
                ];
            }
        }
    }
    let mm = (value / MM).ceil().clamp(i16::MIN as f64, i16::MAX as f64) as i16;
    let b = mm.to_le_bytes();
    [b[0], b[1], 0, 0]
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use std::collections::HashSet;

    /// `merged` gives what the k-way merge by (key, index) with the first of each key
    /// kept gives (itertools' `kmerge` and `dedup_by`, the previous way): up to seven runs with
    /// their offsets, keys from a small range (many shared between runs) or a wide one, empty
    /// runs among them.
    #[test]
    fn merged_runs_keep_the_earliest_of_each_key() {
        use itertools::Itertools;
        let mut rng = rand::rngs::StdRng::seed_from_u64(17);
        for trial in 0..400 {
            let k = trial % 8;
            let span = if trial % 2 == 0 { 6 } else { 1 << 20 };
            let mut next_index = 0u32;
            let runs: Vec<Vec<(SeenKey, u32)>> = (0..k)
                .map(|_| {
                    let n = rng.random_range(0..60);
                    let mut keys: Vec<SeenKey> = (0..n)
                        .map(|_| {
                            let c = |rng: &mut rand::rngs::StdRng| rng.random_range(-span..span);
                            (
                                c(&mut rng),
                                c(&mut rng),
                                c(&mut rng),
                                rng.random_range(0..3),
                            )
                        })
                        .collect();
                    keys.sort_unstable();
                    keys.dedup();
                    // Indices distinct across runs, in no particular order within one.
                    let mut run: Vec<(SeenKey, u32)> = keys
                        .into_iter()
                        .map(|key| {
                            next_index += rng.random_range(1..4);
                            (key, next_index)
                        })
                        .collect();
                    let m = run.len();
                    for i in 0..m {
                        let j = rng.random_range(i..m);
                        let (a, b) = (run[i].1, run[j].1);
                        (run[i].1, run[j].1) = (b, a);
                    }
                    run
                })
                .collect();
            let want: Vec<(SeenKey, u32)> = runs
                .iter()
                .map(|r| r.iter().copied())
                .kmerge()
                .dedup_by(|a, b| a.0 == b.0)
                .collect();
            // Each run's indices from its least, offset by it as a path's are; every other
            // run's keys packed as a path keeps them (when they fit).
            let offset: Vec<(u32, Vec<(SeenKey, u32)>)> = runs
                .iter()
                .map(|r| {
                    let start = r.iter().map(|e| e.1).min().unwrap_or(0);
                    (start, r.iter().map(|&(k, i)| (k, i - start)).collect())
                })
                .collect();
            let packed: Vec<PathKeys> = offset
                .iter()
                .map(|(_, k)| PathKeys::of(k.clone()))
                .collect();
            let runs = offset
                .iter()
                .zip(&packed)
                .enumerate()
                .map(|(j, ((start, keys), packed))| Run {
                    keys: match j % 2 {
                        0 => RunKeys::Pairs(keys.into()),
                        _ => packed.run(0..packed.len()),
                    },
                    start: *start,
                })
                .collect();
            assert_eq!(merged(runs).collect::<Vec<_>>(), want, "trial {trial}");
        }
    }

    /// The de-duplication as it was specified: one sphere at a time, each looked up in a hash
    /// set of the keys added before it.
    fn one_by_one(
        model: &RobotModel,
        sweep: &mut Sweep,
        seen: &mut HashSet<SeenKey>,
        p: &[PathSphere],
    ) {
        for s in p {
            if seen.insert(seen_key(s)) {
                let radius = model.spheres[s.sphere as usize].radius;
                sweep.spheres.push(SphereSample {
                    centre: s.centre,
                    radius,
                    capsule: 0,
                });
                if sweep
                    .kept
                    .insert(feature_key(&s.centre, radius, sweep.feature_spacing))
                {
                    sweep.features.push((s.centre, radius));
                }
            }
        }
    }

    /// Paths that revisit each other's spheres (and their own, often at once) on the 0.2 mm
    /// key grid, with keys that differ in one coordinate or in the sphere only, added in
    /// batches of several paths: the sorted merges keep exactly the spheres, features and keys
    /// of the one-by-one lookups, in the same order.
    #[test]
    fn merged_keys_keep_what_one_by_one_lookups_keep() {
        let model = prf_files::robot::example().unwrap();
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let (mut sorted, mut reference) = (Sweep::default(), Sweep::default());
        let mut seen = HashSet::new();
        for batch in 0..40 {
            let paths: Vec<SweptPath> = (0..rng.random_range(1..4))
                .map(|_| {
                    let n = rng.random_range(0..400);
                    // The last grid point per sphere: a third of the spheres stay on it (the
                    // robot near its base or at rest), with a different centre in the cell.
                    let mut at = [[0i32; 3]; 3];
                    let mut spheres = Vec::new();
                    for _ in 0..n {
                        let sphere = rng.random_range(0..3u8);
                        let at = &mut at[sphere as usize];
                        if rng.random_bool(0.67) {
                            *at = core::array::from_fn(|_| rng.random_range(-6..6));
                        }
                        let mut c = || rng.random_range(-0.4..0.4) * 2e-4;
                        let centre = Vector3::new(
                            at[0] as f64 * 2e-4 + c(),
                            at[1] as f64 * 2e-4 + c(),
                            at[2] as f64 * 2e-4 + c(),
                        );
                        spheres.push(PathSphere { centre, sphere });
                    }
                    SweptPath::new(&spheres)
                })
                .collect();
            sorted.add_spheres(&model, &paths.iter().collect::<Vec<_>>());
            for p in &paths {
                one_by_one(
                    &model,
                    &mut reference,
                    &mut seen,
                    &p.spheres().collect::<Vec<_>>(),
                );
            }
            let ball = |s: SphereSample| (s.centre, s.radius);
            assert!(
                sorted
                    .spheres
                    .iter()
                    .map(ball)
                    .eq(reference.spheres.iter().map(ball)),
                "batch {batch}"
            );
            // Each sphere names a piece of path it lies on.
            for s in sorted.spheres.iter() {
                let k = &sorted.capsules[s.capsule as usize];
                let p = prf_shared::field::nearest_on_segment(&s.centre, &k.a, &k.b);
                assert!((p - s.centre).norm() <= crate::capsule::TOLERANCE + 1e-12);
            }
            assert_eq!(sorted.features, reference.features, "batch {batch}");
            let mut keys: Vec<SeenKey> = seen.iter().copied().collect();
            keys.sort_unstable();
            assert_eq!(sorted.seen.to_vec(), keys, "batch {batch}");
        }
        // The key grid is 12³ × 3 spheres: most later spheres are duplicates.
        assert!(sorted.spheres.len() > 1000 && sorted.spheres.len() < 12 * 12 * 12 * 3);
    }

    /// The keys of a path, sorted and de-duplicated (packed into `u64`, or as tuples when the
    /// extent is too wide), are those a `BTreeMap` keeps: each key once, with its earliest
    /// sphere.
    #[test]
    fn sorted_keys_keep_the_earliest_sphere_of_each() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(11);
        for (case, reach) in [1, 5, 3000, 1 << 20, i32::MAX]
            .into_iter()
            .cycle()
            .take(40)
            .enumerate()
        {
            let n = rng.random_range(0..3000);
            let mut keys: Vec<(SeenKey, u32)> = Vec::new();
            let mut index = 0;
            for _ in 0..n {
                index += rng.random_range(1..4);
                let mut c = || rng.random_range(-reach..=reach.saturating_sub(1));
                let (x, y, z) = (c(), c(), c());
                keys.push(((x, y, z, rng.random_range(0..42)), index));
            }
            let mut reference = std::collections::BTreeMap::new();
            for (k, i) in &keys {
                reference.entry(*k).or_insert(*i);
            }
            let sorted = PathKeys::of(keys);
            assert_eq!(
                sorted.to_vec(),
                reference.into_iter().collect::<Vec<_>>(),
                "case {case}"
            );
            // Packed whenever the fields fit: always at a reach of a few thousand grid steps.
            let packs = matches!(sorted, PathKeys::Packed(..));
            assert_eq!(packs, n > 0 && reach <= 3000, "case {case}");
        }
    }

    /// The keys `SweptPath::of` gathers one sphere at a time ([`RawKeys`], each in a word of
    /// offsets from the first) sort to exactly the keys the pairs sort to, packing included:
    /// within a few grid steps and within metres (packed), and beyond the words' ±26 m (taken
    /// again from the spheres; pairs, too wide to pack).
    #[test]
    fn raw_keys_sort_as_their_pairs_do() {
        let mut rng = rand::rngs::StdRng::seed_from_u64(23);
        for (case, reach) in [2, 7_000, 150_000, 1 << 24]
            .into_iter()
            .cycle()
            .take(24)
            .enumerate()
        {
            let n = rng.random_range(0..2000);
            let first: [i32; 3] = core::array::from_fn(|_| rng.random_range(-20_000..20_000));
            let spheres: Vec<PathSphere> = (0..n)
                .map(|_| {
                    // On the key grid, up to 0.4 steps off it.
                    let mut c = |f: i32| {
                        let k = f + rng.random_range(-reach..=reach);
                        (k as f64 + rng.random_range(-0.4..0.4)) * 2e-4
                    };
                    let centre = Vector3::new(c(first[0]), c(first[1]), c(first[2]));
                    PathSphere {
                        centre,
                        sphere: rng.random_range(0..42),
                    }
                })
                .collect();
            let mut raw = RawKeys::with_capacity(n);
            let mut pairs = Vec::new();
            for (i, s) in spheres.iter().enumerate() {
                raw.push(seen_key(s));
                pairs.push((seen_key(s), i as u32));
            }
            let records = RecordBytes::written(&[], &spheres);
            let (wide, from_raw) = (raw.wide, raw.sorted(&records));
            assert_eq!(from_raw, PathKeys::of(pairs), "case {case}");
            assert_eq!(wide, reach > 1 << 17, "case {case}");
            let packed = matches!(from_raw, PathKeys::Packed(..));
            assert_eq!(packed, n > 0 && reach <= 7_000, "case {case}");
        }
    }

    /// The margin learning uses: the setting, capped where ε leaves a sphere's own
    /// certificate ball less room, and at least 1 mm.
    #[test]
    fn the_margin_is_capped_by_epsilon() {
        let cfg = WorkspaceConfig::default();
        assert_eq!(cfg.margin_for(0.02), REUSE_MARGIN);
        assert!((cfg.margin_for(0.008) - 0.0075).abs() < 1e-15);
        assert_eq!(cfg.margin_for(0.0), 0.001);
    }

    /// Leaving out a sphere that repeats its robot sphere's last key (`SweptPath::of`)
    /// changes nothing a sweep keeps: one-by-one lookups over every sphere of every
    /// configuration keep the same spheres, in the same order.
    #[test]
    fn repeated_spheres_left_out_add_nothing_a_sweep_keeps() {
        let model = prf_files::robot::example().unwrap();
        let base = Pose::from_parts(
            nalgebra::Translation3::new(0.3, -0.2, 0.1),
            nalgebra::UnitQuaternion::from_euler_angles(0.0, 0.0, 0.7),
        );
        // Joints 1–3 at rest for the first half (the spheres near the base repeat), then all
        // moving; a pause in the middle (every sphere repeats).
        let arm: Vec<[f64; 7]> = (0..300)
            .map(|k| {
                let t = (k.min(200) as f64 / 100.0).max(0.0);
                let moving = |j: usize| if j < 3 && k < 150 { 0.0 } else { t };
                core::array::from_fn(|j| 0.3 * moving(j) * (1.0 + j as f64 / 7.0))
            })
            .collect();
        let mut every = Vec::new();
        for q in &arm {
            let mut c = [Vector3::zeros(); MAX_SPHERES];
            prf_shared::kinematics::ArmKinematics::new(&model, &JointVector::from(*q))
                .sphere_centres(&model, &mut c);
            for (j, c) in c[..model.spheres.len()].iter().enumerate() {
                every.push(PathSphere {
                    centre: base.transform_point(&(*c).into()).coords,
                    sphere: j as u8,
                });
            }
        }
        // A step wider than any move: one configuration per sample, as `every` has.
        let path = SweptPath::of(&model, &base, &arm, 10.0);
        assert!(
            path.len() < every.len() * 3 / 4,
            "{} of {}",
            path.len(),
            every.len()
        );
        let (mut left_out, mut all) = (Sweep::default(), Sweep::default());
        let spheres: Vec<PathSphere> = path.spheres().collect();
        one_by_one(&model, &mut left_out, &mut HashSet::new(), &spheres);
        one_by_one(&model, &mut all, &mut HashSet::new(), &every);
        assert_eq!(left_out.spheres, all.spheres);
        assert_eq!(path, SweptPath::new(&spheres));
    }
}
