//! Time parameterisation of a joint-space polyline within speed, acceleration and jerk
//! limits: linear segments joined by parabolic blends around the via points (LSPB),
//! synchronised over all axes, then smoothed by a moving average over a window w, as a
//! controller's jerk filter does. The LSPB's acceleration is piecewise constant with
//! |a| ≤ a_max; the average's jerk is (a(t) − a(t − w))/w, so w = 2·a_max/j_max keeps every
//! axis within its jerk limit, and averaging keeps speed and acceleration within theirs. The
//! motion starts and ends at rest with zero acceleration. With `blend = false` the LSPB stops
//! at every via point and follows the polyline exactly.

/// Per-axis limits.
#[derive(Clone, Copy, Debug)]
pub struct Limits<const N: usize> {
    pub speed: [f64; N],
    pub acceleration: [f64; N],
    pub jerk: [f64; N],
}

/// One LSPB motion through a polyline.
#[derive(Clone, Debug)]
pub struct Lspb<const N: usize> {
    waypoints: Vec<[f64; N]>,
    /// Velocity of each linear segment.
    velocity: Vec<[f64; N]>,
    /// Time of each via point (centre of its blend).
    via_time: Vec<f64>,
    /// Blend duration at each via point.
    blend: Vec<f64>,
}

impl<const N: usize> Lspb<N> {
    /// Times the polyline `waypoints` (≥ 1 point) with every axis within `limits`.
    pub fn new(waypoints: &[[f64; N]], limits: &Limits<N>) -> Self {
        assert!(
            !waypoints.is_empty(),
            "a motion needs at least one waypoint"
        );
        let m = waypoints.len() - 1;
        // Segment durations from the speed limits, then stretched until blends fit.
        let mut seg: Vec<f64> = (0..m)
            .map(|k| {
                (0..N)
                    .map(|j| (waypoints[k + 1][j] - waypoints[k][j]).abs() / limits.speed[j])
                    .fold(1e-3, f64::max)
            })
            .collect();
        loop {
            let velocity = velocities(waypoints, &seg);
            let blend: Vec<f64> = (0..=m)
                .map(|i| {
                    let before = if i == 0 { [0.0; N] } else { velocity[i - 1] };
                    let after = if i == m { [0.0; N] } else { velocity[i] };
                    (0..N)
                        .map(|j| (after[j] - before[j]).abs() / limits.acceleration[j])
                        .fold(0.0, f64::max)
                })
                .collect();
            let mut ok = true;
            for k in 0..m {
                if blend[k] / 2.0 + blend[k + 1] / 2.0 > seg[k] * (1.0 + 1e-12) {
                    seg[k] *= 1.02;
                    ok = false;
                }
            }
            if ok {
                let mut via_time = vec![blend[0] / 2.0];
                for k in 0..m {
                    via_time.push(via_time[k] + seg[k]);
                }
                return Lspb {
                    waypoints: waypoints.to_vec(),
                    velocity,
                    via_time,
                    blend,
                };
            }
        }
    }

    pub fn duration(&self) -> f64 {
        self.via_time.last().copied().unwrap_or(0.0)
            + self.blend.last().copied().unwrap_or(0.0) / 2.0
    }

    /// Position at time t (clamped to [0, duration]).
    pub fn at(&self, t: f64) -> [f64; N] {
        let t = t.clamp(0.0, self.duration());
        let m = self.waypoints.len() - 1;
        for i in 0..=m {
            let (ti, bi) = (self.via_time[i], self.blend[i]);
            let before = if i == 0 {
                [0.0; N]
            } else {
                self.velocity[i - 1]
            };
            if t <= ti + bi / 2.0 {
                if t >= ti - bi / 2.0 && bi > 0.0 {
                    let after = if i == m { [0.0; N] } else { self.velocity[i] };
                    let s = t - ti + bi / 2.0;
                    return std::array::from_fn(|j| {
                        self.waypoints[i][j]
                            + before[j] * (t - ti)
                            + (after[j] - before[j]) * s * s / (2.0 * bi)
                    });
                }
                // Linear part of the segment arriving at via i.
                return std::array::from_fn(|j| self.waypoints[i][j] + before[j] * (t - ti));
            }
        }
        self.waypoints[m]
    }
}

fn velocities<const N: usize>(w: &[[f64; N]], seg: &[f64]) -> Vec<[f64; N]> {
    (0..seg.len())
        .map(|k| std::array::from_fn(|j| (w[k + 1][j] - w[k][j]) / seg[k]))
        .collect()
}

/// A timed motion: one blended LSPB, or one LSPB per segment (exact stops at via points),
/// smoothed by the jerk filter.
#[derive(Clone, Debug)]
pub struct Motion<const N: usize> {
    pieces: Vec<Lspb<N>>,
    /// Window w of the moving average, s.
    window: f64,
    /// Times where the LSPB's acceleration jumps (blend ends, piece ends), sorted: between
    /// them its position is a quadratic.
    breaks: Vec<f64>,
}

impl<const N: usize> Motion<N> {
    pub fn new(waypoints: &[[f64; N]], limits: &Limits<N>, blend: bool) -> Self {
        let pieces: Vec<Lspb<N>> = if blend || waypoints.len() <= 2 {
            vec![Lspb::new(waypoints, limits)]
        } else {
            waypoints.windows(2).map(|w| Lspb::new(w, limits)).collect()
        };
        let window = (0..N)
            .map(|j| 2.0 * limits.acceleration[j] / limits.jerk[j])
            .fold(0.0, f64::max);
        let mut breaks = vec![0.0];
        let mut start = 0.0;
        for p in &pieces {
            for (&ti, &bi) in p.via_time.iter().zip(&p.blend) {
                breaks.extend([start + ti - bi / 2.0, start + ti + bi / 2.0]);
            }
            start += p.duration();
            breaks.push(start);
        }
        breaks.sort_by(f64::total_cmp);
        Motion {
            pieces,
            window,
            breaks,
        }
    }

    /// Duration of the smoothed motion: the LSPB's plus the filter window.
    pub fn duration(&self) -> f64 {
        self.lspb_duration() + self.window
    }

    fn lspb_duration(&self) -> f64 {
        self.pieces.iter().map(Lspb::duration).sum()
    }

    /// Position at time t (clamped to [0, duration]): the mean of the LSPB over [t − w, t],
    /// integrated exactly (two-point Gauss–Legendre on each quadratic piece).
    pub fn at(&self, t: f64) -> [f64; N] {
        let t = t.clamp(0.0, self.duration());
        if self.window <= 0.0 {
            return self.lspb_at(t);
        }
        let (a, b) = (t - self.window, t);
        let mut sum = [0.0; N];
        let mut lo = a;
        let inside = self.breaks.iter().copied().filter(|&x| x > a && x < b);
        for hi in inside.chain(std::iter::once(b)) {
            let (m, h) = ((lo + hi) / 2.0, (hi - lo) / 2.0);
            let g = h / 3f64.sqrt();
            let (p, q) = (self.lspb_at(m - g), self.lspb_at(m + g));
            for j in 0..N {
                sum[j] += h * (p[j] + q[j]);
            }
            lo = hi;
        }
        sum.map(|v| v / self.window)
    }

    /// Position of the unfiltered LSPB at time t (held before 0 and after its end).
    fn lspb_at(&self, mut t: f64) -> [f64; N] {
        for p in &self.pieces {
            let d = p.duration();
            if t <= d {
                return p.at(t);
            }
            t -= d;
        }
        self.pieces
            .last()
            .map(|p| p.at(p.duration()))
            .unwrap_or([0.0; N])
    }

    pub fn start(&self) -> [f64; N] {
        self.at(0.0)
    }

    pub fn end(&self) -> [f64; N] {
        self.at(self.duration())
    }
}
