//! The sphere kernel: forward kinematics of eight or sixteen configurations in lanes, then
//! sphere tests with early exit. Written once over [`Lanes`]; [`super::dispatch`] instantiates
//! it for AVX-512, AVX2 and the portable lanes.
//!
//! Per batch:
//!
//! 1. Forward kinematics, base to tip: every body frame (rotation columns and origin, twelve
//!    lane vectors) from its parent's, for all configurations at once; each revolute
//!    joint costs one [`sin_cos`] and twelve multiply–adds (plus 27 when its placement's
//!    rotation is not a signed permutation).
//! 2. Environment, distal links first: a link's bounding sphere against the obstacles (sorted
//!    by distance, culled by reach); only if some lane touches one, its spheres one by one.
//! 3. Self-collision, pair by pair of links: bounding spheres, then sphere pairs.
//!
//! The batch is valid only if every lane is: the first touch anywhere ends the check.

use super::environment::{Environment, Shape};
use super::lanes::{Lanes, Wide, sin_cos};
use super::robot::{FastLink, Motion, Rot, SphereRobot};

/// A body frame in lanes, stored: rotation columns `[0..9]` (column-major), origin `[9..12]`.
pub(crate) type FrameStore = [Wide; 12];

struct Frame<L> {
    r: [[L; 3]; 3],
    t: [L; 3],
}

impl<L: Lanes> Frame<L> {
    #[inline(always)]
    fn load(s: &FrameStore) -> Self {
        Self {
            r: [
                [L::load(&s[0]), L::load(&s[1]), L::load(&s[2])],
                [L::load(&s[3]), L::load(&s[4]), L::load(&s[5])],
                [L::load(&s[6]), L::load(&s[7]), L::load(&s[8])],
            ],
            t: [L::load(&s[9]), L::load(&s[10]), L::load(&s[11])],
        }
    }

    #[inline(always)]
    fn store(&self, s: &mut FrameStore) {
        for j in 0..3 {
            for i in 0..3 {
                self.r[j][i].store(&mut s[3 * j + i]);
            }
            self.t[j].store(&mut s[9 + j]);
        }
    }

    /// `R c + t` for a constant point `c`.
    #[inline(always)]
    fn point(&self, c: &[f32; 4]) -> [L; 3] {
        let mut p = self.t;
        for (i, pi) in p.iter_mut().enumerate() {
            *pi = self.r[0][i].mul_add_s(
                c[0],
                self.r[1][i].mul_add_s(c[1], self.r[2][i].mul_add_s(c[2], *pi)),
            );
        }
        p
    }
}

#[inline(always)]
fn scaled<L: Lanes>(v: [L; 3], s: L) -> [L; 3] {
    [v[0].mul(s), v[1].mul(s), v[2].mul(s)]
}

/// Forward kinematics of the batch `q` (eight values per coordinate) into `frames`.
#[inline(always)]
pub(crate) fn forward<L: Lanes>(robot: &SphereRobot, q: &[Wide], frames: &mut [FrameStore]) {
    let base = Frame {
        r: [
            splat3(robot.base_rot[0]),
            splat3(robot.base_rot[1]),
            splat3(robot.base_rot[2]),
        ],
        t: splat3(robot.base_trans),
    };
    for (b, j) in robot.joints.iter().enumerate() {
        let parent = if j.parent == u32::MAX {
            None
        } else {
            Some(Frame::<L>::load(&frames[j.parent as usize]))
        };
        let p = parent.as_ref().unwrap_or(&base);
        // Origin: parent origin + parent rotation · placement translation (zeros skipped).
        let mut t = p.t;
        for (k, &x) in j.trans.iter().enumerate() {
            if x != 0.0 {
                for (i, ti) in t.iter_mut().enumerate() {
                    *ti = p.r[k][i].mul_add_s(x, *ti);
                }
            }
        }
        let qv = L::load(&q[j.q as usize]);
        let r = match (j.motion, j.rot) {
            (Motion::Revolute, Rot::Perm { col, sign }) => {
                let (s, c) = sin_cos(qv);
                let (q0, q1, q2) = (
                    p.r[col[0] as usize],
                    p.r[col[1] as usize],
                    p.r[col[2] as usize],
                );
                // Signs folded into the scalars: column j of Q is sign[j] · q_j.
                let (c0, s1) = (c.mul(L::splat(sign[0])), s.mul(L::splat(sign[1])));
                let (c1, s0) = (c.mul(L::splat(sign[1])), s.mul(L::splat(sign[0])));
                let r0 = [
                    q0[0].mul_add(c0, q1[0].mul(s1)),
                    q0[1].mul_add(c0, q1[1].mul(s1)),
                    q0[2].mul_add(c0, q1[2].mul(s1)),
                ];
                let r1 = [
                    q1[0].mul_add(c1, q0[0].mul(s0).neg()),
                    q1[1].mul_add(c1, q0[1].mul(s0).neg()),
                    q1[2].mul_add(c1, q0[2].mul(s0).neg()),
                ];
                let r2 = if sign[2] > 0.0 { q2 } else { neg3(q2) };
                [r0, r1, r2]
            }
            (Motion::Revolute, Rot::General(m)) => {
                let qm = mat_mul(&p.r, &m);
                let (s, c) = sin_cos(qv);
                let r0 = [
                    qm[0][0].mul_add(c, qm[1][0].mul(s)),
                    qm[0][1].mul_add(c, qm[1][1].mul(s)),
                    qm[0][2].mul_add(c, qm[1][2].mul(s)),
                ];
                let r1 = [
                    qm[1][0].mul_add(c, qm[0][0].mul(s).neg()),
                    qm[1][1].mul_add(c, qm[0][1].mul(s).neg()),
                    qm[1][2].mul_add(c, qm[0][2].mul(s).neg()),
                ];
                [r0, r1, qm[2]]
            }
            (Motion::Prismatic, rot) => {
                let qm = match rot {
                    Rot::Perm { col, sign } => {
                        let mut m = p.r;
                        for k in 0..3 {
                            let v = p.r[col[k] as usize];
                            m[k] = if sign[k] > 0.0 { v } else { neg3(v) };
                        }
                        m
                    }
                    Rot::General(m) => mat_mul(&p.r, &m),
                };
                let d = scaled(qm[2], qv);
                t = [t[0].add(d[0]), t[1].add(d[1]), t[2].add(d[2])];
                qm
            }
        };
        Frame { r, t }.store(&mut frames[b]);
    }
}

/// `a · m` with `m` constant (both column-major).
#[inline(always)]
fn mat_mul<L: Lanes>(a: &[[L; 3]; 3], m: &[[f32; 3]; 3]) -> [[L; 3]; 3] {
    let mut out = *a;
    for (j, col) in m.iter().enumerate() {
        for i in 0..3 {
            out[j][i] = a[0][i].mul_add_s(
                col[0],
                a[1][i].mul_add_s(col[1], a[2][i].mul(L::splat(col[2]))),
            );
        }
    }
    out
}

#[inline(always)]
fn splat3<L: Lanes>(v: [f32; 3]) -> [L; 3] {
    [L::splat(v[0]), L::splat(v[1]), L::splat(v[2])]
}

#[inline(always)]
fn neg3<L: Lanes>(v: [L; 3]) -> [L; 3] {
    [v[0].neg(), v[1].neg(), v[2].neg()]
}

#[inline(always)]
fn dot3<L: Lanes>(a: [L; 3], b: [f32; 3]) -> L {
    a[0].mul_add_s(b[0], a[1].mul_add_s(b[1], a[2].mul(L::splat(b[2]))))
}

/// Whether the batch is decided for lanes `live` given the lanes `hit` in collision: with
/// `ANY`, as soon as one of them collides; otherwise when all of them do.
#[inline(always)]
fn done<const ANY: bool>(hit: u32, live: u32) -> bool {
    if ANY {
        hit & live != 0
    } else {
        hit & live == live
    }
}

/// The lanes in which a sphere (centre `p`, radius `r`) touches an obstacle (stopping as
/// [`done`] says for lanes `live`).
#[inline(always)]
fn sphere_env<L: Lanes, const ANY: bool>(env: &Environment, p: [L; 3], r: f32, live: u32) -> u32 {
    let o = env.origin;
    let d = [
        p[0].sub(L::splat(o[0])),
        p[1].sub(L::splat(o[1])),
        p[2].sub(L::splat(o[2])),
    ];
    let reach = d[0]
        .mul_add(d[0], d[1].mul_add(d[1], d[2].mul(d[2])))
        .sqrt()
        .add(L::splat(r));
    let mut hit = 0;
    for ob in &env.obstacles {
        if reach.all_lt(L::splat(ob.min_distance)) {
            return hit;
        }
        hit |= match ob.shape {
            Shape::Sphere { c, r: rr } => {
                let (x, y, z) = (
                    p[0].sub(L::splat(c[0])),
                    p[1].sub(L::splat(c[1])),
                    p[2].sub(L::splat(c[2])),
                );
                let rs = r + rr;
                touches(x.mul_add(x, y.mul_add(y, z.mul(z))), rs * rs)
            }
            Shape::Cuboid { c, axes, half } => {
                let v = [
                    p[0].sub(L::splat(c[0])),
                    p[1].sub(L::splat(c[1])),
                    p[2].sub(L::splat(c[2])),
                ];
                let zero = L::splat(0.0);
                let g0 = dot3(v, axes[0]).abs().sub(L::splat(half[0])).max(zero);
                let g1 = dot3(v, axes[1]).abs().sub(L::splat(half[1])).max(zero);
                let g2 = dot3(v, axes[2]).abs().sub(L::splat(half[2])).max(zero);
                touches(g0.mul_add(g0, g1.mul_add(g1, g2.mul(g2))), r * r)
            }
            Shape::Cylinder { c, u, h, r: rr } => {
                let v = [
                    p[0].sub(L::splat(c[0])),
                    p[1].sub(L::splat(c[1])),
                    p[2].sub(L::splat(c[2])),
                ];
                let t = dot3(v, u);
                let d2 = v[0].mul_add(v[0], v[1].mul_add(v[1], v[2].mul(v[2])));
                let zero = L::splat(0.0);
                let radial = d2.sub(t.mul(t)).max(zero).sqrt();
                let gr = radial.sub(L::splat(rr)).max(zero);
                let ga = t.abs().sub(L::splat(h)).max(zero);
                touches(gr.mul_add(gr, ga.mul(ga)), r * r)
            }
            Shape::Capsule { a, u, len, r: rr } => {
                let v = [
                    p[0].sub(L::splat(a[0])),
                    p[1].sub(L::splat(a[1])),
                    p[2].sub(L::splat(a[2])),
                ];
                let t = dot3(v, u).max(L::splat(0.0)).min(L::splat(len));
                let w = [
                    v[0].sub(t.mul(L::splat(u[0]))),
                    v[1].sub(t.mul(L::splat(u[1]))),
                    v[2].sub(t.mul(L::splat(u[2]))),
                ];
                let rs = r + rr;
                touches(
                    w[0].mul_add(w[0], w[1].mul_add(w[1], w[2].mul(w[2]))),
                    rs * rs,
                )
            }
            // n · p − d ≤ r.
            Shape::HalfSpace { n, d } => dot3(p, n).lt_mask(L::splat(next_up(d + r))),
        };
        if done::<ANY>(hit, live) {
            return hit;
        }
    }
    hit
}

/// The next float above a finite `x`.
#[inline(always)]
fn next_up(x: f32) -> f32 {
    if x >= 0.0 {
        // Also −0.0, whose successor is the smallest positive float as well.
        f32::from_bits(x.abs().to_bits() + 1)
    } else {
        f32::from_bits(x.to_bits() - 1)
    }
}

/// The lanes where `d² ≤ limit` (touching counts).
#[inline(always)]
fn touches<L: Lanes>(d2: L, limit: f32) -> u32 {
    // d² ≤ limit ⟺ d² < the next float above limit.
    d2.lt_mask(L::splat(next_up(limit)))
}

#[inline(always)]
fn link_frame<'f, L: Lanes>(
    link: &FastLink,
    frames: &[FrameStore],
    cache: &'f mut Option<Frame<L>>,
) -> Option<&'f Frame<L>> {
    if link.body == u32::MAX {
        return None;
    }
    if cache.is_none() {
        *cache = Some(Frame::load(&frames[link.body as usize]));
    }
    cache.as_ref()
}

/// World centre of sphere `s` of a link (fixed links store world centres).
#[inline(always)]
fn centre<L: Lanes>(frame: Option<&Frame<L>>, s: &[f32; 4]) -> [L; 3] {
    match frame {
        Some(f) => f.point(s),
        None => [L::splat(s[0]), L::splat(s[1]), L::splat(s[2])],
    }
}

/// Whether every lane of the batch `q` is free of collisions.
#[inline(always)]
pub(crate) fn batch_valid<L: Lanes>(
    robot: &SphereRobot,
    env: &Environment,
    q: &[Wide],
    frames: &mut [FrameStore],
) -> bool {
    batch::<L, true>(robot, env, q, frames, L::full()) == 0
}

/// The lanes of `live` in which the batch `q` collides (all of `live` checked).
#[inline(always)]
pub(crate) fn batch_mask<L: Lanes>(
    robot: &SphereRobot,
    env: &Environment,
    q: &[Wide],
    frames: &mut [FrameStore],
    live: u32,
) -> u32 {
    batch::<L, false>(robot, env, q, frames, live) & live
}

/// The lanes in collision, stopping as [`done`] says for lanes `live`.
#[inline(always)]
fn batch<L: Lanes, const ANY: bool>(
    robot: &SphereRobot,
    env: &Environment,
    q: &[Wide],
    frames: &mut [FrameStore],
    live: u32,
) -> u32 {
    forward::<L>(robot, q, frames);
    let frames = &*frames;
    let mut hit = 0u32;
    // Environment: body, then link, then sphere; a lane already in collision needs no more.
    for &gi in &robot.env_order {
        let g = &robot.groups[gi as usize];
        let f = Frame::<L>::load(&frames[g.body as usize]);
        let need = live & !hit;
        if sphere_env::<L, true>(env, f.point(&g.bound), g.bound[3], need) & need == 0 {
            continue;
        }
        for &li in &g.links {
            let link = &robot.links[li as usize];
            let need = live & !hit;
            if g.links.len() > 1
                && sphere_env::<L, true>(env, f.point(&link.bound), link.bound[3], need) & need == 0
            {
                continue;
            }
            let spheres = &robot.spheres[link.first as usize..(link.first + link.count) as usize];
            for s in spheres {
                hit |= sphere_env::<L, ANY>(env, f.point(s), s[3], live & !hit);
                if done::<ANY>(hit, live) {
                    return hit;
                }
            }
        }
    }
    // Self-collision: body pairs, then link pairs, then spheres.
    for gp in &robot.group_pairs {
        let (ga, gb) = (&robot.groups[gp.a as usize], &robot.groups[gp.b as usize]);
        let (mut ca, mut cb) = (None, None);
        let fa = group_frame::<L>(ga.body, frames, &mut ca);
        let fb = group_frame::<L>(gb.body, frames, &mut cb);
        let need = live & !hit;
        if spheres_touch(
            centre(fa, &ga.bound),
            centre(fb, &gb.bound),
            ga.bound[3] + gb.bound[3],
        ) & need
            == 0
        {
            continue;
        }
        for &(ia, ib) in &gp.links {
            hit |= links_touch::<L, ANY>(robot, ia, ib, fa, fb, live & !hit);
            if done::<ANY>(hit, live) {
                return hit;
            }
        }
    }
    hit
}

/// The frame of a body, loaded once (`None` for the world: fixed spheres are stored in world
/// coordinates).
#[inline(always)]
fn group_frame<'f, L: Lanes>(
    body: u32,
    frames: &[FrameStore],
    cache: &'f mut Option<Frame<L>>,
) -> Option<&'f Frame<L>> {
    if body == u32::MAX {
        return None;
    }
    if cache.is_none() {
        *cache = Some(Frame::load(&frames[body as usize]));
    }
    cache.as_ref()
}

/// The lanes of `live` in which links `ia` and `ib` touch (stopping as [`done`] says).
#[inline(always)]
fn links_touch<L: Lanes, const ANY: bool>(
    robot: &SphereRobot,
    ia: u16,
    ib: u16,
    fa: Option<&Frame<L>>,
    fb: Option<&Frame<L>>,
    live: u32,
) -> u32 {
    let (la, lb) = (&robot.links[ia as usize], &robot.links[ib as usize]);
    let (pa, pb) = (centre(fa, &la.bound), centre(fb, &lb.bound));
    if spheres_touch(pa, pb, la.bound[3] + lb.bound[3]) & live == 0 {
        return 0;
    }
    let sa = &robot.spheres[la.first as usize..(la.first + la.count) as usize];
    let sb = &robot.spheres[lb.first as usize..(lb.first + lb.count) as usize];
    let mut hit = 0;
    for s in sa {
        let p = centre(fa, s);
        // A sphere clear of the other link's bounding sphere is clear of all its spheres.
        if spheres_touch(p, pb, s[3] + lb.bound[3]) & live & !hit == 0 {
            continue;
        }
        for t in sb {
            hit |= spheres_touch(p, centre(fb, t), s[3] + t[3]) & live;
            if done::<ANY>(hit, live) {
                return hit;
            }
        }
    }
    hit
}

#[inline(always)]
fn spheres_touch<L: Lanes>(a: [L; 3], b: [L; 3], rs: f32) -> u32 {
    let (x, y, z) = (a[0].sub(b[0]), a[1].sub(b[1]), a[2].sub(b[2]));
    touches(x.mul_add(x, y.mul_add(y, z.mul(z))), rs * rs)
}

/// What touches what in lane 0 of `q` (for messages and diagnostics; portable lanes, no early
/// exit): `(link, None)` for a link sphere touching obstacle … , `(link, Some(other link))` for
/// self-collision.
pub(crate) fn contacts(
    robot: &SphereRobot,
    env: &Environment,
    q: &[Wide],
    frames: &mut [FrameStore],
) -> Vec<(usize, Option<usize>, usize)> {
    use super::lanes::Portable;
    type L = Portable;
    forward::<L>(robot, q, frames);
    let frames = &*frames;
    let lane0 = |p: [L; 3], f: &dyn Fn([L; 3]) -> u32| {
        // Lane 0 broadcast, so other lanes cannot answer for it.
        f([
            L::splat(p[0].to_wide()[0]),
            L::splat(p[1].to_wide()[0]),
            L::splat(p[2].to_wide()[0]),
        ]) != 0
    };
    let mut out = Vec::new();
    for (li, link) in robot.links.iter().enumerate() {
        if link.body == u32::MAX {
            continue;
        }
        let mut cache = None;
        let f = link_frame::<L>(link, frames, &mut cache);
        for s in &robot.spheres[link.first as usize..(link.first + link.count) as usize] {
            let p = centre(f, s);
            for (oi, ob) in env.obstacles.iter().enumerate() {
                let single = Environment {
                    origin: env.origin,
                    obstacles: vec![*ob],
                };
                if lane0(p, &|p| sphere_env::<L, true>(&single, p, s[3], L::full())) {
                    out.push((li, None, oi));
                }
            }
        }
    }
    for &(ia, ib) in &robot.self_pairs {
        let (la, lb) = (&robot.links[ia as usize], &robot.links[ib as usize]);
        let (mut ca, mut cb) = (None, None);
        let fa = link_frame::<L>(la, frames, &mut ca);
        let fb = link_frame::<L>(lb, frames, &mut cb);
        let hit = robot.spheres[la.first as usize..(la.first + la.count) as usize]
            .iter()
            .any(|s| {
                robot.spheres[lb.first as usize..(lb.first + lb.count) as usize]
                    .iter()
                    .any(|t| {
                        let (p, q) = (centre(fa, s), centre(fb, t));
                        let p0 = p.map(|v| L::splat(v.to_wide()[0]));
                        let q0 = q.map(|v| L::splat(v.to_wide()[0]));
                        spheres_touch(p0, q0, s[3] + t[3]) != 0
                    })
            });
        if hit {
            out.push((ia as usize, Some(ib as usize), 0));
        }
    }
    out
}

/// Every sphere's world centre and radius in lane 0 of `q` (portable lanes).
pub(crate) fn world_spheres(
    robot: &SphereRobot,
    q: &[Wide],
    frames: &mut [FrameStore],
) -> Vec<(usize, [f32; 3], f32)> {
    use super::lanes::Portable;
    forward::<Portable>(robot, q, frames);
    let mut out = Vec::new();
    for (li, link) in robot.links.iter().enumerate() {
        let mut cache = None;
        let f = link_frame::<Portable>(link, frames, &mut cache);
        for s in &robot.spheres[link.first as usize..(link.first + link.count) as usize] {
            let c = centre(f, s);
            out.push((
                li,
                [c[0].to_wide()[0], c[1].to_wide()[0], c[2].to_wide()[0]],
                s[3],
            ));
        }
    }
    out
}
