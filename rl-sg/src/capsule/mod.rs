//! The control-rate distance path: links as capsules, distances without allocation.
//!
//! A safety function inside the real-time loop (speed and separation monitoring, a tracked
//! worker's distance to the arm) needs the robot–obstacle distance every cycle, with a bound on
//! its time and nothing that can block. Exact mesh distances (the [`crate::Scene`] queries) are
//! too slow and allocate; this path approximates every link by a few capsules — a sphere is a
//! capsule of zero length — that *contain* the link's geometry (generated from its meshes by
//! [`crate::fit`], with a proof of containment in its docs and a test that samples surface
//! points), so the distance it reports is never larger than the true one: it errs on the safe
//! side by at most the capsules' padding.
//!
//! [`CapsuleModel`] holds up to `N` capsules in fixed arrays, each attached to a body of an
//! rl-core [`Model`](rl_core::Model) (or to the world). Per cycle:
//!
//! 1. [`rl_core::algo::forward_position`] (the controller does it anyway);
//! 2. [`CapsuleModel::update`]: every capsule to the world frame (one rigid transform each);
//! 3. [`CapsuleModel::min_distance`] to obstacle spheres or capsules, [`CapsuleModel::
//!    min_self_distance`] over chosen link pairs, or [`CapsuleModel::any_closer_than`] (stops at
//!    the first pair under a threshold).
//!
//! Cost: O(capsules × obstacles) point–segment or segment–segment distances, each a few dozen
//! flops; a square root only when a pair can beat the best so far. `#![no_std]`, no allocator,
//! no panics (indices out of range are skipped, capacity is a `Result`), no locks.
//!
//! ```
//! use glam::DVec3;
//! use rl_sg::capsule::{Capsule, CapsuleModel, LinkCapsule};
//!
//! let mut arm = CapsuleModel::<8>::new();
//! // A 0.5 m link of radius 5 cm along x, attached to the world.
//! arm.push(LinkCapsule::on_world(0, Capsule::new(DVec3::ZERO, DVec3::X * 0.5, 0.05))).unwrap();
//! arm.update_world_only();
//! let worker = [Capsule::sphere(DVec3::new(0.25, 0.3, 0.0), 0.1)];
//! let d = arm.min_distance(&worker).unwrap();
//! assert!((d.distance - 0.15).abs() < 1e-12);
//! ```

mod segment;

pub use segment::{inverse_length_squared, point_segment_parameter, segment_segment_parameters};

use core::fmt;

use glam::DVec3;
use rl_core::Data;
use rl_core::model::ROOT;
use rl_core::spatial::PlueckerTransform;
use rl_core::task::Proximity;

/// A capsule: the points within `radius` of the segment from `a` to `b` (a sphere when
/// `a == b`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Capsule {
    /// One end of the axis segment, m.
    pub a: DVec3,
    /// The other end, m.
    pub b: DVec3,
    /// Radius, m.
    pub radius: f64,
}

impl Capsule {
    /// A capsule around the segment `a`–`b`.
    pub const fn new(a: DVec3, b: DVec3, radius: f64) -> Self {
        Self { a, b, radius }
    }

    /// A sphere (a capsule of zero length).
    pub const fn sphere(center: DVec3, radius: f64) -> Self {
        Self {
            a: center,
            b: center,
            radius,
        }
    }

    /// Whether this is a sphere (zero length).
    pub fn is_sphere(&self) -> bool {
        self.a == self.b
    }

    /// The same capsule seen from the frame that `x` maps into (`x` maps capsule coordinates to
    /// that frame's).
    #[inline]
    pub fn transformed(&self, x: &PlueckerTransform) -> Self {
        Self {
            a: x.rotation * self.a + x.translation,
            b: x.rotation * self.b + x.translation,
            radius: self.radius,
        }
    }

    /// Distance from `p` to the capsule's surface (negative inside).
    pub fn signed_distance_to_point(&self, p: DVec3) -> f64 {
        let d = self.b - self.a;
        let t = point_segment_parameter(p, self.a, d, inverse_length_squared(d));
        (p - (self.a + d * t)).length() - self.radius
    }

    /// Whether `p` lies in the capsule, with `tolerance` m of slack.
    pub fn contains_point(&self, p: DVec3, tolerance: f64) -> bool {
        self.signed_distance_to_point(p) <= tolerance
    }

    /// Signed distance to `other` (negative: the depth of overlap) and the closest points on
    /// both surfaces (for overlapping capsules, the deepest points along the axis between the
    /// two segments' closest points).
    pub fn distance(&self, other: &Capsule) -> (f64, DVec3, DVec3) {
        let (d1, d2) = (self.b - self.a, other.b - other.a);
        let (s, t) = segment_segment_parameters(self.a, d1, other.a, d2);
        witness(self.a + d1 * s, self.radius, other.a + d2 * t, other.radius)
    }
}

/// Signed distance and surface points of two balls centred on `c1`, `c2`.
#[inline]
fn witness(c1: DVec3, r1: f64, c2: DVec3, r2: f64) -> (f64, DVec3, DVec3) {
    let v = c2 - c1;
    let len = v.length();
    // Coincident centres: any direction is as good; x keeps the result deterministic.
    let n = if len > 0.0 { v / len } else { DVec3::X };
    (len - r1 - r2, c1 + n * r1, c2 - n * r2)
}

/// A capsule fixed to a body of a kinematic model.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinkCapsule {
    /// The rl-core body it moves with, or [`ROOT`] for the world.
    pub body: usize,
    /// An index of the caller's (e.g. into a list of link names), reported back in results.
    pub link: u16,
    /// The capsule in the body's frame.
    pub local: Capsule,
}

impl LinkCapsule {
    /// A capsule fixed to rl-core body `body`.
    pub const fn new(body: usize, link: u16, local: Capsule) -> Self {
        Self { body, link, local }
    }

    /// A capsule fixed to the world.
    pub const fn on_world(link: u16, capsule: Capsule) -> Self {
        Self {
            body: ROOT,
            link,
            local: capsule,
        }
    }
}

/// A capsule in the world frame, with what the distance loops need precomputed.
#[derive(Clone, Copy, Debug, PartialEq)]
struct WorldCapsule {
    a: DVec3,
    /// `b − a`.
    d: DVec3,
    /// `1 / (d·d)`, 0 for a sphere.
    inv_dd: f64,
    radius: f64,
}

impl WorldCapsule {
    #[inline(always)]
    fn from_capsule(c: &Capsule) -> Self {
        let d = c.b - c.a;
        Self {
            a: c.a,
            d,
            inv_dd: inverse_length_squared(d),
            radius: c.radius,
        }
    }
}

/// The result of a capsule distance query: the closest pair and its points (world frame).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CapsuleDistance {
    /// Index of the model's capsule.
    pub capsule: usize,
    /// The [`LinkCapsule::link`] of that capsule.
    pub link: u16,
    /// Index of the obstacle (or, for self-distance, of the other capsule).
    pub other: usize,
    /// Signed distance, m (negative: overlap depth).
    pub distance: f64,
    /// Closest point on the model's capsule.
    pub point: DVec3,
    /// Closest point on the other one.
    pub other_point: DVec3,
}

/// A model has room for no more capsules.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CapacityError {
    /// The capacity.
    pub capacity: usize,
}

impl fmt::Display for CapacityError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "capsule model full: capacity {}", self.capacity)
    }
}

/// Up to `N` capsules fixed to the bodies of a kinematic model, in fixed arrays.
///
/// The world-frame capsules are kept as a structure of arrays (one array per coordinate), so
/// the loop over capsules for one obstacle sphere compiles to vector instructions.
#[derive(Clone, Debug)]
pub struct CapsuleModel<const N: usize> {
    local: [LinkCapsule; N],
    /// Local axis vectors `b − a` and their `1/(d·d)` (a rigid motion keeps the length).
    local_d: [DVec3; N],
    inv_dd: [f64; N],
    radius: [f64; N],
    ax: [f64; N],
    ay: [f64; N],
    az: [f64; N],
    dx: [f64; N],
    dy: [f64; N],
    dz: [f64; N],
    len: usize,
}

impl<const N: usize> Default for CapsuleModel<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> CapsuleModel<N> {
    /// An empty model.
    pub const fn new() -> Self {
        Self {
            local: [LinkCapsule::on_world(0, Capsule::sphere(DVec3::ZERO, 0.0)); N],
            local_d: [DVec3::ZERO; N],
            inv_dd: [0.0; N],
            radius: [0.0; N],
            ax: [0.0; N],
            ay: [0.0; N],
            az: [0.0; N],
            dx: [0.0; N],
            dy: [0.0; N],
            dz: [0.0; N],
            len: 0,
        }
    }

    /// A capsule of radius `radius` along every link of `model`'s skeleton: from each body's
    /// origin to each child's joint and to each tool on it (a sphere at the origin of a body
    /// with neither). For models without collision geometry (a URDF of frames and inertias);
    /// fitting capsules to meshes ([`crate::fit`]) is tighter. An error when they do not fit.
    pub fn skeleton<const B: usize>(
        model: &rl_core::Model<B>,
        radius: f64,
    ) -> Result<Self, CapacityError> {
        let mut m = Self::new();
        for b in 0..model.body_count() {
            let mut ends = 0;
            let link = u16::try_from(b).unwrap_or(u16::MAX);
            for c in (b + 1)..model.body_count() {
                if model.parent(c) == b {
                    let end = model.placement(c).translation;
                    m.push(LinkCapsule::new(
                        b,
                        link,
                        Capsule::new(DVec3::ZERO, end, radius),
                    ))?;
                    ends += 1;
                }
            }
            for t in model.tools().iter().filter(|t| t.body == b) {
                let end = t.placement.translation;
                m.push(LinkCapsule::new(
                    b,
                    link,
                    Capsule::new(DVec3::ZERO, end, radius),
                ))?;
                ends += 1;
            }
            if ends == 0 {
                m.push(LinkCapsule::new(
                    b,
                    link,
                    Capsule::sphere(DVec3::ZERO, radius),
                ))?;
            }
        }
        Ok(m)
    }

    /// Adds a capsule; its world pose is that of the last update (the local one until then).
    pub fn push(&mut self, c: LinkCapsule) -> Result<(), CapacityError> {
        if self.len == N {
            return Err(CapacityError { capacity: N });
        }
        let i = self.len;
        let d = c.local.b - c.local.a;
        self.local[i] = c;
        self.local_d[i] = d;
        self.inv_dd[i] = inverse_length_squared(d);
        self.radius[i] = c.local.radius;
        self.set_world(i, c.local.a, d);
        self.len += 1;
        Ok(())
    }

    #[inline(always)]
    fn set_world(&mut self, i: usize, a: DVec3, d: DVec3) {
        self.ax[i] = a.x;
        self.ay[i] = a.y;
        self.az[i] = a.z;
        self.dx[i] = d.x;
        self.dy[i] = d.y;
        self.dz[i] = d.z;
    }

    #[inline(always)]
    fn world(&self, i: usize) -> WorldCapsule {
        WorldCapsule {
            a: DVec3::new(self.ax[i], self.ay[i], self.az[i]),
            d: DVec3::new(self.dx[i], self.dy[i], self.dz[i]),
            inv_dd: self.inv_dd[i],
            radius: self.radius[i],
        }
    }

    /// The number of capsules.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// The capsules as given.
    pub fn capsules(&self) -> &[LinkCapsule] {
        &self.local[..self.len]
    }

    /// Capsule `i` in the world frame, as of the last update.
    pub fn world_capsule(&self, i: usize) -> Option<Capsule> {
        (i < self.len).then(|| {
            let w = self.world(i);
            Capsule {
                a: w.a,
                b: w.a + w.d,
                radius: w.radius,
            }
        })
    }

    /// Moves every capsule to the world frame from the body poses in `data` (those of the last
    /// [`rl_core::algo::forward_position`]). A body index beyond `data` leaves its capsule
    /// where it was. Does not allocate.
    #[inline]
    pub fn update<const B: usize>(&mut self, data: &Data<B>) {
        for i in 0..self.len {
            let l = &self.local[i];
            let (a, d) = if l.body == ROOT {
                (l.local.a, self.local_d[i])
            } else if l.body < B {
                let x = data.world_pose(l.body);
                (
                    x.rotation * l.local.a + x.translation,
                    x.rotation * self.local_d[i],
                )
            } else {
                continue;
            };
            self.set_world(i, a, d);
        }
    }

    /// Places every capsule from its local pose alone (for models fixed to the world).
    pub fn update_world_only(&mut self) {
        for i in 0..self.len {
            let (a, d) = (self.local[i].local.a, self.local_d[i]);
            self.set_world(i, a, d);
        }
    }

    /// The closest pair between the model and `obstacles` (spheres or capsules, world frame),
    /// or `None` when either is empty. Spheres take a vectorised point–segment pass over the
    /// capsules. Does not allocate.
    pub fn min_distance(&self, obstacles: &[Capsule]) -> Option<CapsuleDistance> {
        let n = self.len;
        if n == 0 || obstacles.is_empty() {
            return None;
        }
        let mut best = (f64::INFINITY, usize::MAX, usize::MAX);
        for (j, o) in obstacles.iter().enumerate() {
            let (d, i) = if o.a == o.b {
                self.sphere_pass(o.a, o.radius, best.0)
            } else {
                let ow = WorldCapsule::from_capsule(o);
                let mut b = (f64::INFINITY, usize::MAX);
                for i in 0..n {
                    let (p, q) = closest(&self.world(i), &ow);
                    let d = (p - q).length() - self.radius[i] - o.radius;
                    if d < b.0 {
                        b = (d, i);
                    }
                }
                b
            };
            if i != usize::MAX && (d < best.0 || best.1 == usize::MAX) {
                best = (d, i, j);
            }
        }
        let (_, i, j) = best;
        if i == usize::MAX {
            // Only NaNs: no answer rather than a made-up one.
            return None;
        }
        Some(self.result(i, j, &WorldCapsule::from_capsule(&obstacles[j])))
    }

    /// The pair's closest points and signed distance.
    fn result(&self, i: usize, j: usize, o: &WorldCapsule) -> CapsuleDistance {
        let w = self.world(i);
        let (p, q) = closest(&w, o);
        let (distance, point, other_point) = witness(p, w.radius, q, o.radius);
        CapsuleDistance {
            capsule: i,
            link: self.local[i].link,
            other: j,
            distance,
            point,
            other_point,
        }
    }

    /// The smallest distance below `bound` from sphere `(c, r)` to the capsules, and the
    /// capsule (`(bound, usize::MAX)` when none is closer): blocks of eight capsules in
    /// branch-free loops of fixed length the compiler vectorises (entries past the last capsule
    /// are computed and ignored). A block whose squared axis distances all exceed
    /// `(bound + radii)²` cannot win and takes no square root.
    #[inline(always)]
    fn sphere_pass(&self, c: DVec3, r: f64, bound: f64) -> (f64, usize) {
        const W: usize = 8;
        let n = self.len;
        let mut best = (bound, usize::MAX);
        let mut start = 0;
        while start < n {
            let m = W.min(n - start);
            let mut dist = [f64::INFINITY; W];
            if let Some((d2, rad)) = self.block_squared(c, start) {
                let mut near = false;
                for k in 0..W {
                    let reach = (best.0 + rad[k] + r).max(0.0);
                    near |= d2[k] < reach * reach;
                }
                if near || !best.0.is_finite() {
                    for ((out, &s), &ra) in dist.iter_mut().zip(&d2).zip(rad) {
                        *out = sqrt(s) - ra - r;
                    }
                }
            } else {
                // The last, partial block of a capacity that is no multiple of eight.
                for (k, out) in dist.iter_mut().enumerate().take(m) {
                    let i = start + k;
                    *out = sqrt(self.squared(c, i)) - self.radius[i] - r;
                }
            }
            for (k, &d) in dist[..m].iter().enumerate() {
                if d < best.0 {
                    best = (d, start + k);
                }
            }
            start += m;
        }
        best
    }

    /// The closest pair among `pairs` of the model's own capsules (e.g. the link pairs an SRDF
    /// does not exclude); pairs with an index out of range are skipped. Does not allocate.
    pub fn min_self_distance(&self, pairs: &[(u16, u16)]) -> Option<CapsuleDistance> {
        let mut best = (f64::INFINITY, usize::MAX, usize::MAX);
        for &(i, j) in pairs {
            let (i, j) = (usize::from(i), usize::from(j));
            if i >= self.len || j >= self.len {
                continue;
            }
            let (p, q) = closest(&self.world(i), &self.world(j));
            let d = (p - q).length() - self.radius[i] - self.radius[j];
            if d < best.0 {
                best = (d, i, j);
            }
        }
        let (_, i, j) = best;
        (i != usize::MAX).then(|| self.result(i, j, &self.world(j)))
    }

    /// Whether any capsule is closer than `threshold` m to any obstacle; stops at the first.
    pub fn any_closer_than(&self, obstacles: &[Capsule], threshold: f64) -> bool {
        for o in obstacles {
            let ow = WorldCapsule::from_capsule(o);
            for i in 0..self.len {
                let w = self.world(i);
                let reach = threshold + w.radius + o.radius;
                if reach < 0.0 {
                    continue;
                }
                let (p, q) = closest(&w, &ow);
                if (p - q).length_squared() < reach * reach {
                    return true;
                }
            }
        }
        false
    }

    /// The robot's points nearest to `obstacles` for a task-space law's repulsion
    /// ([`rl_core::task::Proximity`]): for every capsule moving with a body its nearest
    /// obstacle, then the (up to `out.len()`) capsules closest to theirs among those nearer
    /// than `within` m, nearest first, into `out`; returns how many. Each proximity is the
    /// point of the capsule's surface nearest to the obstacle, the unit normal from the obstacle
    /// to it, the signed distance and the obstacle's velocity (for its approach's damping;
    /// ones). `velocities[j]` is obstacle `j`'s (zero past the end of the slice: at rest).
    /// Capsules fixed to the world are skipped. Does not allocate.
    pub fn proximities(
        &self,
        obstacles: &[Capsule],
        velocities: &[DVec3],
        within: f64,
        out: &mut [Proximity],
    ) -> usize {
        let n = self.len;
        let mut best = [f64::INFINITY; N];
        let mut of = [usize::MAX; N];
        for (j, o) in obstacles.iter().enumerate() {
            if o.a == o.b {
                self.sphere_distances(o.a, o.radius, j, within, &mut best, &mut of);
            } else {
                let ow = WorldCapsule::from_capsule(o);
                for i in 0..n {
                    let (p, q) = closest(&self.world(i), &ow);
                    let d = (p - q).length() - self.radius[i] - o.radius;
                    if d < best[i] {
                        best[i] = d;
                        of[i] = j;
                    }
                }
            }
        }
        let mut count = 0;
        while count < out.len() {
            // The nearest capsule not taken yet (taken ones are marked by `of = MAX`).
            let mut pick = usize::MAX;
            for i in 0..n {
                let moving = self.local[i].body != ROOT;
                if moving
                    && of[i] != usize::MAX
                    && best[i] < within
                    && (pick == usize::MAX || best[i] < best[pick])
                {
                    pick = i;
                }
            }
            if pick == usize::MAX {
                break;
            }
            let w = self.world(pick);
            let o = WorldCapsule::from_capsule(&obstacles[of[pick]]);
            let (p, q) = closest(&w, &o);
            let v = p - q;
            let len = v.length();
            // Centres that coincide: any direction; z keeps it deterministic.
            let normal = if len > 0.0 { v / len } else { DVec3::Z };
            out[count] = Proximity {
                obstacle_velocity: velocities.get(of[pick]).copied().unwrap_or(DVec3::ZERO),
                ..Proximity::at_rest(
                    self.local[pick].body,
                    p - normal * w.radius,
                    normal,
                    len - w.radius - o.radius,
                )
            };
            of[pick] = usize::MAX;
            count += 1;
        }
        count
    }

    /// For each capsule, the distance to sphere `(c, r)` (index `j`) where it beats `best` and
    /// `within`: blocks of eight capsules in branch-free loops the compiler vectorises; a block
    /// whose squared axis distances all exceed `(min(best, within) + radii)²` takes no square
    /// root.
    #[inline(always)]
    fn sphere_distances(
        &self,
        c: DVec3,
        r: f64,
        j: usize,
        within: f64,
        best: &mut [f64; N],
        of: &mut [usize; N],
    ) {
        const W: usize = 8;
        let n = self.len;
        let mut start = 0;
        while start < n {
            let m = W.min(n - start);
            if let Some((d2, rad)) = self.block_squared(c, start) {
                let mut near = false;
                for k in 0..W {
                    let bk = best.get(start + k).copied().unwrap_or(f64::INFINITY);
                    let reach = (bk.min(within) + rad[k] + r).max(0.0);
                    near |= d2[k] < reach * reach;
                }
                if !near {
                    start += m;
                    continue;
                }
                for k in 0..m {
                    let d = sqrt(d2[k]) - rad[k] - r;
                    if d < best[start + k] {
                        best[start + k] = d;
                        of[start + k] = j;
                    }
                }
            } else {
                // The last, partial block of a capacity that is no multiple of eight.
                for i in start..start + m {
                    let d = sqrt(self.squared(c, i)) - self.radius[i] - r;
                    if d < best[i] {
                        best[i] = d;
                        of[i] = j;
                    }
                }
            }
            start += m;
        }
    }

    /// For each capsule, its distance to the nearest obstacle, into `out[i]` (`out` shorter
    /// than the model: the rest is not computed; longer: the tail is left as it is). Does not
    /// allocate.
    pub fn distances_per_capsule(&self, obstacles: &[Capsule], out: &mut [f64]) {
        for (i, slot) in out.iter_mut().enumerate().take(self.len) {
            let w = self.world(i);
            let mut d = f64::INFINITY;
            for o in obstacles {
                let (p, q) = closest(&w, &WorldCapsule::from_capsule(o));
                d = d.min((p - q).length() - w.radius - o.radius);
            }
            *slot = d;
        }
    }
}

impl<const N: usize> CapsuleModel<N> {
    /// The squared distances from `c` to the axes of the eight capsules from `start` (entries
    /// past the last capsule are computed and ignored) and their radii, in a branch-free loop
    /// the compiler vectorises; `None` where the capacity has no eight from there.
    #[inline(always)]
    fn block_squared(&self, c: DVec3, start: usize) -> Option<([f64; 8], &[f64; 8])> {
        let (ax, ay, az) = (
            block(&self.ax, start)?,
            block(&self.ay, start)?,
            block(&self.az, start)?,
        );
        let (dx, dy, dz) = (
            block(&self.dx, start)?,
            block(&self.dy, start)?,
            block(&self.dz, start)?,
        );
        let (inv, rad) = (block(&self.inv_dd, start)?, block(&self.radius, start)?);
        let mut d2 = [0.0; 8];
        for k in 0..8 {
            d2[k] = point_segment_squared(c, ax[k], ay[k], az[k], dx[k], dy[k], dz[k], inv[k]);
        }
        Some((d2, rad))
    }

    /// The squared distance from `c` to capsule `i`'s axis.
    #[inline(always)]
    fn squared(&self, c: DVec3, i: usize) -> f64 {
        point_segment_squared(
            c,
            self.ax[i],
            self.ay[i],
            self.az[i],
            self.dx[i],
            self.dy[i],
            self.dz[i],
            self.inv_dd[i],
        )
    }
}

/// Eight entries of `a` from `start`, if the array has them.
#[inline(always)]
fn block(a: &[f64], start: usize) -> Option<&[f64; 8]> {
    a.get(start..start + 8).and_then(|s| s.try_into().ok())
}

/// Squared distance from `c` to the segment `a + t·d`, `t ∈ [0, 1]`, given `inv = 1/(d·d)`.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn point_segment_squared(
    c: DVec3,
    ax: f64,
    ay: f64,
    az: f64,
    dx: f64,
    dy: f64,
    dz: f64,
    inv: f64,
) -> f64 {
    let (px, py, pz) = (c.x - ax, c.y - ay, c.z - az);
    let t = ((px * dx + py * dy + pz * dz) * inv).clamp(0.0, 1.0);
    let (ex, ey, ez) = (px - dx * t, py - dy * t, pz - dz * t);
    ex * ex + ey * ey + ez * ez
}

/// The square root: the compiler's (vectorisable) with std, libm's without.
#[inline(always)]
fn sqrt(x: f64) -> f64 {
    #[cfg(feature = "std")]
    {
        x.sqrt()
    }
    #[cfg(not(feature = "std"))]
    {
        libm::sqrt(x)
    }
}

/// Closest points of the axes of two world capsules.
#[inline(always)]
fn closest(w: &WorldCapsule, o: &WorldCapsule) -> (DVec3, DVec3) {
    let (s, t) = segment_segment_parameters(w.a, w.d, o.a, o.d);
    (w.a + w.d * s, o.a + o.d * t)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_against_capsule_side_and_cap() {
        let c = Capsule::new(DVec3::ZERO, DVec3::new(1.0, 0.0, 0.0), 0.1);
        let (d, p, q) = c.distance(&Capsule::sphere(DVec3::new(0.5, 1.0, 0.0), 0.2));
        assert!((d - 0.7).abs() < 1e-15);
        assert!((p - DVec3::new(0.5, 0.1, 0.0)).length() < 1e-15);
        assert!((q - DVec3::new(0.5, 0.8, 0.0)).length() < 1e-15);
        let (d, ..) = c.distance(&Capsule::sphere(DVec3::new(2.0, 0.0, 0.0), 0.2));
        assert!((d - 0.7).abs() < 1e-15);
        // Overlap is a negative distance.
        let (d, ..) = c.distance(&Capsule::sphere(DVec3::new(0.5, 0.2, 0.0), 0.2));
        assert!((d + 0.1).abs() < 1e-15);
    }

    #[test]
    fn the_model_finds_the_closest_pair_and_respects_capacity() {
        let mut m = CapsuleModel::<2>::new();
        m.push(LinkCapsule::on_world(
            7,
            Capsule::new(DVec3::ZERO, DVec3::X, 0.1),
        ))
        .unwrap();
        m.push(LinkCapsule::on_world(
            9,
            Capsule::sphere(DVec3::new(0.0, 5.0, 0.0), 0.5),
        ))
        .unwrap();
        assert_eq!(
            m.push(LinkCapsule::on_world(0, Capsule::sphere(DVec3::ZERO, 1.0))),
            Err(CapacityError { capacity: 2 })
        );
        let obstacles = [
            Capsule::sphere(DVec3::new(0.5, 3.0, 0.0), 0.1),
            Capsule::new(DVec3::new(-1.0, 4.0, 1.0), DVec3::new(1.0, 4.0, 1.0), 0.05),
        ];
        let d = m.min_distance(&obstacles).unwrap();
        // The sphere link at y = 5 against the capsule at y = 4, z = 1: √2 − 0.55.
        assert_eq!((d.capsule, d.link, d.other), (1, 9, 1));
        assert!((d.distance - (2f64.sqrt() - 0.55)).abs() < 1e-12);
        let mut per = [0.0; 2];
        m.distances_per_capsule(&obstacles, &mut per);
        assert!((per[0] - 2.8).abs() < 1e-12 && (per[1] - d.distance).abs() < 1e-12);
        assert!(m.any_closer_than(&obstacles, 0.9));
        assert!(!m.any_closer_than(&obstacles, 0.8));
        let s = m.min_self_distance(&[(0, 1), (0, 9)]).unwrap();
        assert!((s.distance - (5.0 - 0.6)).abs() < 1e-12);
        assert!(CapsuleModel::<2>::new().min_distance(&obstacles).is_none());
        assert!(m.min_distance(&[]).is_none());
    }

    #[test]
    fn proximities_are_the_nearest_capsules_with_their_surface_points_and_normals() {
        let mut rng = rl_core::algo::ik::SplitMix64::new(7);
        let mut r = || rng.next_f64() * 2.0 - 1.0;
        let data = Data::<2>::new();
        for round in 0..40 {
            let mut m = CapsuleModel::<20>::new();
            for i in 0..17 {
                let a = DVec3::new(r(), r(), r());
                let b = if i % 4 == 0 {
                    a
                } else {
                    a + DVec3::new(r(), r(), r()) * 0.3
                };
                // Body 0 (identity in a fresh `Data`), two on the world (never reported).
                let body = if i % 8 == 5 { ROOT } else { 0 };
                m.push(LinkCapsule::new(
                    body,
                    i,
                    Capsule::new(a, b, 0.05 + 0.05 * r().abs()),
                ))
                .unwrap();
            }
            m.update(&data);
            let mut obstacles = [Capsule::sphere(DVec3::ZERO, 0.0); 6];
            for (k, o) in obstacles.iter_mut().enumerate() {
                let c = DVec3::new(r(), r(), r()) * 1.2;
                let e = if k % 2 == 0 {
                    c
                } else {
                    c + DVec3::new(r(), r(), r()) * 0.2
                };
                *o = Capsule::new(c, e, 0.1 * r().abs());
            }
            let within = if round % 2 == 0 { 0.3 } else { f64::INFINITY };
            // Brute force: every moving capsule's nearest obstacle, sorted.
            let mut want: Vec<f64> = (0..m.len())
                .filter(|&i| m.capsules()[i].body != ROOT)
                .map(|i| {
                    let w = m.world_capsule(i).unwrap();
                    obstacles
                        .iter()
                        .map(|o| w.distance(o).0)
                        .fold(f64::INFINITY, f64::min)
                })
                .filter(|d| *d < within)
                .collect();
            want.sort_by(f64::total_cmp);
            let mut out = [Proximity::at_rest(0, DVec3::ZERO, DVec3::X, 0.0); 4];
            let k = m.proximities(&obstacles, &[], within, &mut out);
            assert_eq!(k, want.len().min(4));
            for (p, d) in out[..k].iter().zip(&want) {
                assert!((p.distance - d).abs() < 1e-12, "{p:?} vs {d}");
                assert!((p.normal.length() - 1.0).abs() < 1e-12);
                assert_eq!(p.body, 0);
                // On the surface of its capsule, `distance` from the nearest obstacle along
                // the normal.
                let on_surface = (0..m.len())
                    .filter_map(|i| m.world_capsule(i))
                    .map(|c| c.signed_distance_to_point(p.point).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(on_surface < 1e-12);
                if p.distance <= 0.0 {
                    // Overlapping: the points are the deepest along the axis, not nearest.
                    continue;
                }
                let to_obstacle = obstacles
                    .iter()
                    .map(|o| o.signed_distance_to_point(p.point))
                    .fold(f64::INFINITY, f64::min);
                assert!(
                    (to_obstacle - p.distance).abs() < 1e-9,
                    "{to_obstacle} {p:?}"
                );
                let back = p.point - p.normal * p.distance;
                let at = obstacles
                    .iter()
                    .map(|o| o.signed_distance_to_point(back).abs())
                    .fold(f64::INFINITY, f64::min);
                assert!(at < 1e-9, "{at}");
            }
        }
    }

    #[test]
    fn blocks_and_pruning_match_brute_force() {
        let mut rng = rl_core::algo::ik::SplitMix64::new(0x9e37_79b9_7f4a_7c15);
        let mut r = || rng.next_f64() * 2.0 - 1.0;
        // Capacities that are and are not multiples of the block width; spheres and capsules.
        for n in [1usize, 7, 8, 9, 17, 23] {
            let mut m = CapsuleModel::<24>::new();
            let mut caps = [Capsule::sphere(DVec3::ZERO, 0.0); 24];
            for (i, c) in caps.iter_mut().enumerate().take(n) {
                let a = DVec3::new(r(), r(), r());
                let b = if i % 3 == 0 {
                    a
                } else {
                    a + DVec3::new(r(), r(), r()) * 0.3
                };
                *c = Capsule::new(a, b, 0.05 + 0.05 * r().abs());
                m.push(LinkCapsule::on_world(i as u16, *c)).unwrap();
            }
            m.update_world_only();
            for _ in 0..50 {
                let obstacles = [
                    Capsule::sphere(DVec3::new(r(), r(), r()) * 1.5, 0.1 * r().abs()),
                    Capsule::sphere(DVec3::new(r(), r(), r()) * 1.5, 0.1 * r().abs()),
                    Capsule::new(DVec3::new(r(), r(), r()), DVec3::new(r(), r(), r()), 0.02),
                ];
                let d = m.min_distance(&obstacles).unwrap();
                let mut brute = f64::INFINITY;
                for c in &caps[..n] {
                    for o in &obstacles {
                        brute = brute.min(c.distance(o).0);
                    }
                }
                assert!(
                    (d.distance - brute).abs() < 1e-12,
                    "n {n}: {} vs {brute}",
                    d.distance
                );
                let again = caps[d.capsule].distance(&obstacles[d.other]).0;
                assert!((again - d.distance).abs() < 1e-12);
            }
        }
    }
}
