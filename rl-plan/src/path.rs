//! A path: waypoints of a [`JointSpace`], stored one after the other.

use crate::space::JointSpace;

/// Waypoints, each `nq` numbers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Path {
    nq: usize,
    points: Vec<f64>,
}

impl Path {
    /// An empty path of configurations of `nq` numbers.
    pub fn new(nq: usize) -> Self {
        Self {
            nq,
            points: Vec::new(),
        }
    }

    /// A path through `points` (each of length `nq`).
    pub fn from_points(nq: usize, points: &[Vec<f64>]) -> Self {
        let mut p = Self::new(nq);
        for q in points {
            p.push(q);
        }
        p
    }

    /// Writes the path as CSV: a header naming every number of a configuration
    /// ([`JointSpace::number_names`]: joints, and a rotation's quaternion components), then
    /// one row per waypoint (rad or m; quaternions `x, y, z, w`).
    pub fn write_csv(
        &self,
        space: &JointSpace,
        mut out: impl std::io::Write,
    ) -> std::io::Result<()> {
        let names = space.number_names();
        if names.len() != self.nq {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                format!(
                    "a path of {} numbers per waypoint for a space of {}",
                    self.nq,
                    names.len()
                ),
            ));
        }
        writeln!(out, "{}", names.join(","))?;
        for q in self.points.chunks_exact(self.nq.max(1)) {
            let row: Vec<String> = q.iter().map(|x| format!("{x}")).collect();
            writeln!(out, "{}", row.join(","))?;
        }
        out.flush()
    }

    /// Numbers per waypoint.
    pub fn nq(&self) -> usize {
        self.nq
    }

    /// The number of waypoints.
    pub fn len(&self) -> usize {
        self.points.len().checked_div(self.nq).unwrap_or(0)
    }

    /// Whether it has no waypoint.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Waypoint `i`.
    pub fn point(&self, i: usize) -> &[f64] {
        &self.points[i * self.nq..(i + 1) * self.nq]
    }

    /// Waypoint `i`, mutable.
    pub fn point_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.points[i * self.nq..(i + 1) * self.nq]
    }

    /// Appends a waypoint.
    pub fn push(&mut self, q: &[f64]) {
        self.points.extend_from_slice(&q[..self.nq]);
    }

    /// Inserts a waypoint before index `i`.
    pub fn insert(&mut self, i: usize, q: &[f64]) {
        let at = i * self.nq;
        self.points.splice(at..at, q[..self.nq].iter().copied());
    }

    /// Removes waypoints `range` (indices).
    pub fn remove_range(&mut self, range: std::ops::Range<usize>) {
        self.points
            .drain(range.start * self.nq..range.end * self.nq);
    }

    /// The waypoints, flat.
    pub fn as_flat(&self) -> &[f64] {
        &self.points
    }

    /// The waypoints as vectors.
    pub fn to_vecs(&self) -> Vec<Vec<f64>> {
        (0..self.len()).map(|i| self.point(i).to_vec()).collect()
    }

    /// Reverses the order of the waypoints.
    pub fn reverse(&mut self) {
        let n = self.len();
        for i in 0..n / 2 {
            for k in 0..self.nq {
                self.points.swap(i * self.nq + k, (n - 1 - i) * self.nq + k);
            }
        }
    }

    /// Its length in the space's metric.
    pub fn length(&self, space: &JointSpace) -> f64 {
        space.path_length(&self.points)
    }

    /// The path with extra waypoints so no segment is longer than `max_step` (each segment cut
    /// into equal parts along the geodesic).
    pub fn densified(&self, space: &JointSpace, max_step: f64) -> Path {
        let mut out = Path::new(self.nq);
        if self.is_empty() {
            return out;
        }
        out.push(self.point(0));
        let mut q = vec![0.0; self.nq];
        for i in 1..self.len() {
            let (a, b) = (self.point(i - 1), self.point(i));
            let n = ((space.distance(a, b) / max_step).ceil() as usize).max(1);
            for j in 1..n {
                space.interpolate(a, b, j as f64 / n as f64, &mut q);
                out.push(&q);
            }
            out.push(b);
        }
        out
    }
}
