//! RRT-Connect (Kuffner & LaValle 2000) in joint space, with path shortcutting: the motion
//! planner the programmer of the example cell uses (Sec. 4.3.1).

use rand::{RngExt, rngs::StdRng};

/// Planner effort.
#[derive(Clone, Copy, Debug)]
pub struct RrtConfig {
    /// Maximum tree extensions of one attempt.
    pub max_iterations: usize,
    /// Attempts with fresh trees before giving up (restarts escape an unlucky tree).
    pub attempts: usize,
    /// Largest joint-space step of one extension, rad (Euclidean).
    pub step: f64,
    /// Random shortcut attempts on the found path.
    pub shortcut_attempts: usize,
}

impl Default for RrtConfig {
    fn default() -> Self {
        RrtConfig {
            max_iterations: 10_000,
            attempts: 4,
            step: 0.25,
            shortcut_attempts: 200,
        }
    }
}

/// The planner's view of the robot: a configuration test and a straight-edge test (the edge
/// test may assume its start is already valid).
pub trait Space<const N: usize> {
    fn lower(&self) -> [f64; N];
    fn upper(&self) -> [f64; N];
    fn valid(&self, q: &[f64; N]) -> bool;
    fn edge_valid(&self, a: &[f64; N], b: &[f64; N]) -> bool;
}

/// No path was found.
#[derive(Clone, Debug, PartialEq)]
pub enum RrtError {
    InvalidStart,
    InvalidGoal,
    NoPath { iterations: usize },
}

impl std::fmt::Display for RrtError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RrtError::InvalidStart => write!(f, "start configuration in collision"),
            RrtError::InvalidGoal => write!(f, "goal configuration in collision"),
            RrtError::NoPath { iterations } => write!(f, "no path after {iterations} extensions"),
        }
    }
}

fn dist<const N: usize>(a: &[f64; N], b: &[f64; N]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

fn lerp<const N: usize>(a: &[f64; N], b: &[f64; N], s: f64) -> [f64; N] {
    std::array::from_fn(|i| a[i] + (b[i] - a[i]) * s)
}

struct Tree<const N: usize> {
    nodes: Vec<[f64; N]>,
    parent: Vec<usize>,
}

enum Extend {
    Trapped,
    Advanced(usize),
    Reached(usize),
}

impl<const N: usize> Tree<N> {
    fn new(root: [f64; N]) -> Self {
        Tree {
            nodes: vec![root],
            parent: vec![usize::MAX],
        }
    }

    fn nearest(&self, q: &[f64; N]) -> usize {
        let mut best = (f64::INFINITY, 0);
        for (i, n) in self.nodes.iter().enumerate() {
            let d = dist(n, q);
            if d < best.0 {
                best = (d, i);
            }
        }
        best.1
    }

    fn extend(&mut self, space: &impl Space<N>, q: &[f64; N], step: f64) -> Extend {
        let near = self.nearest(q);
        let from = self.nodes[near];
        let d = dist(&from, q);
        let (new, reached) = if d <= step {
            (*q, true)
        } else {
            (lerp(&from, q, step / d), false)
        };
        if !space.edge_valid(&from, &new) {
            return Extend::Trapped;
        }
        self.nodes.push(new);
        self.parent.push(near);
        let id = self.nodes.len() - 1;
        if reached {
            Extend::Reached(id)
        } else {
            Extend::Advanced(id)
        }
    }

    fn connect(&mut self, space: &impl Space<N>, q: &[f64; N], step: f64) -> Extend {
        loop {
            match self.extend(space, q, step) {
                Extend::Advanced(_) => continue,
                other => return other,
            }
        }
    }

    fn path_to_root(&self, mut i: usize) -> Vec<[f64; N]> {
        let mut out = vec![];
        while i != usize::MAX {
            out.push(self.nodes[i]);
            i = self.parent[i];
        }
        out
    }
}

/// Plans a collision-free polyline from `start` to `goal`, shortcut and with redundant
/// vertices removed.
pub fn plan<const N: usize>(
    space: &impl Space<N>,
    start: [f64; N],
    goal: [f64; N],
    cfg: &RrtConfig,
    rng: &mut StdRng,
) -> Result<Vec<[f64; N]>, RrtError> {
    if !space.valid(&start) {
        return Err(RrtError::InvalidStart);
    }
    if !space.valid(&goal) {
        return Err(RrtError::InvalidGoal);
    }
    if space.edge_valid(&start, &goal) {
        return Ok(vec![start, goal]);
    }
    for _ in 0..cfg.attempts.max(1) {
        if let Some(path) = connect_trees(space, start, goal, cfg, rng) {
            let path = shortcut(space, path, cfg.shortcut_attempts, rng);
            return Ok(prune(space, path));
        }
    }
    Err(RrtError::NoPath {
        iterations: cfg.max_iterations * cfg.attempts.max(1),
    })
}

/// One RRT-Connect attempt: grows a tree from each end until they connect.
fn connect_trees<const N: usize>(
    space: &impl Space<N>,
    start: [f64; N],
    goal: [f64; N],
    cfg: &RrtConfig,
    rng: &mut StdRng,
) -> Option<Vec<[f64; N]>> {
    let (lo, hi) = (space.lower(), space.upper());
    let mut a = Tree::new(start);
    let mut b = Tree::new(goal);
    let mut a_is_start = true;
    for _ in 0..cfg.max_iterations {
        let sample: [f64; N] = std::array::from_fn(|i| rng.random_range(lo[i]..hi[i]));
        if !space.valid(&sample) {
            continue;
        }
        if let Extend::Advanced(n) | Extend::Reached(n) = a.extend(space, &sample, cfg.step) {
            let q_new = a.nodes[n];
            if let Extend::Reached(m) = b.connect(space, &q_new, cfg.step) {
                let (from_start, from_goal) = if a_is_start { (&a, n) } else { (&b, m) };
                let (to_goal, to_goal_id) = if a_is_start { (&b, m) } else { (&a, n) };
                let mut path = from_start.path_to_root(from_goal);
                path.reverse();
                let tail = to_goal.path_to_root(to_goal_id);
                path.extend(tail.into_iter().skip(1));
                return Some(path);
            }
        }
        std::mem::swap(&mut a, &mut b);
        a_is_start = !a_is_start;
    }
    None
}

/// Random shortcutting: join two random points of the path by a straight edge when it is
/// valid.
pub fn shortcut<const N: usize>(
    space: &impl Space<N>,
    mut path: Vec<[f64; N]>,
    attempts: usize,
    rng: &mut StdRng,
) -> Vec<[f64; N]> {
    for _ in 0..attempts {
        if path.len() < 3 {
            break;
        }
        let lengths: Vec<f64> = path.windows(2).map(|w| dist(&w[0], &w[1])).collect();
        let total: f64 = lengths.iter().sum();
        if total <= 0.0 {
            break;
        }
        let mut s = [rng.random_range(0.0..total), rng.random_range(0.0..total)];
        s.sort_by(f64::total_cmp);
        let locate = |mut x: f64| {
            for (k, l) in lengths.iter().enumerate() {
                if x <= *l {
                    return (
                        k,
                        lerp(&path[k], &path[k + 1], if *l > 0.0 { x / l } else { 0.0 }),
                    );
                }
                x -= l;
            }
            let k = lengths.len() - 1;
            (k, path[k + 1])
        };
        let (k1, p1) = locate(s[0]);
        let (k2, p2) = locate(s[1]);
        if k1 == k2 {
            continue;
        }
        if space.edge_valid(&p1, &p2) {
            let mut next = path[..=k1].to_vec();
            next.push(p1);
            next.push(p2);
            next.extend_from_slice(&path[k2 + 1..]);
            path = next;
        }
    }
    path
}

/// Drops vertices whose neighbours can be joined directly.
pub fn prune<const N: usize>(space: &impl Space<N>, path: Vec<[f64; N]>) -> Vec<[f64; N]> {
    let mut out = vec![path[0]];
    let mut k = 0;
    while k + 1 < path.len() {
        // Farthest vertex reachable by one straight edge from path[k].
        let mut j = path.len() - 1;
        while j > k + 1 && !space.edge_valid(&path[k], &path[j]) {
            j -= 1;
        }
        out.push(path[j]);
        k = j;
    }
    out
}
