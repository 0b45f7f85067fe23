//! The motion of one axis as a short sequence of segments of constant jerk, and the shapes the
//! solvers produce (phase durations with their jerk, or with their acceleration or velocity
//! where the next higher limit is infinite).

/// Most segments one axis profile holds: two of braking and the union of the switching times of
/// two seven-phase profiles (a time-synchronised axis blends two, see [`super::sync`]).
pub(crate) const MAX_SEGMENTS: usize = 16;

/// Which derivative a shape sets per phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Order {
    /// Jerk per phase; acceleration, velocity and position are continuous.
    Jerk,
    /// Acceleration per phase (infinite jerk limit); it jumps at phase starts.
    Acceleration,
    /// Velocity per phase (infinite acceleration limit); it jumps at phase starts.
    Velocity,
}

/// Phase durations and the value of `order` in each phase (in the axis' own frame), and the
/// acceleration and velocity after the last phase for the lower orders (whose end state may
/// jump to the target).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Shape {
    pub t: [f64; 7],
    pub value: [f64; 7],
    pub order: Order,
    /// For `Jerk`: the exact acceleration of a zero-jerk phase (a hold at a limit, a cruise at
    /// zero) set at its start instead of the integrated one; NaN keeps the integrated value.
    pub hold: [f64; 7],
    /// For `Jerk`: the exact velocity of phase 3 when it is a cruise at a velocity limit (NaN
    /// otherwise).
    pub cruise: f64,
    pub end_v: f64,
    pub end_a: f64,
}

impl Shape {
    /// The motionless shape of zero duration.
    pub const EMPTY: Self = Self {
        t: [0.0; 7],
        value: [0.0; 7],
        order: Order::Jerk,
        hold: [f64::NAN; 7],
        cruise: f64::NAN,
        end_v: 0.0,
        end_a: 0.0,
    };
}

/// One segment: its start time, its exact length, the state at its start and its constant jerk.
/// Evaluation clamps the time into the segment by its length: after a long phase the absolute
/// start times are rounded to coarser steps than a short phase lasts, and this keeps every
/// sample between the segment's end states (so within the limits they respect).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Segment {
    pub start: f64,
    pub length: f64,
    pub p: f64,
    pub v: f64,
    pub a: f64,
    pub j: f64,
}

impl Segment {
    /// `(p, v, a, j)` at `tau` seconds into the segment.
    #[inline(always)]
    pub fn at(&self, tau: f64) -> [f64; 4] {
        let j = self.j;
        [
            self.p + tau * (self.v + tau * (0.5 * self.a + tau * j * (1.0 / 6.0))),
            self.v + tau * (self.a + 0.5 * tau * j),
            self.a + tau * j,
            j,
        ]
    }
}

/// The motion of one axis: segments from time 0 to [`AxisProfile::duration`], then constant
/// acceleration from the end state (a velocity target keeps moving).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisProfile {
    pub(crate) segments: [Segment; MAX_SEGMENTS],
    pub(crate) len: usize,
    /// Start time of the main (post-braking) part.
    pub(crate) brake_end: f64,
    pub(crate) duration: f64,
    /// State at `duration` (position, velocity, acceleration).
    pub(crate) end: [f64; 3],
}

impl AxisProfile {
    /// An axis resting at `(p, v, a)` from time 0 (a profile of zero duration).
    pub(crate) const fn at_rest(p: f64, v: f64, a: f64) -> Self {
        Self {
            segments: [Segment {
                start: 0.0,
                length: 0.0,
                p: 0.0,
                v: 0.0,
                a: 0.0,
                j: 0.0,
            }; MAX_SEGMENTS],
            len: 0,
            brake_end: 0.0,
            duration: 0.0,
            end: [p, v, a],
        }
    }

    /// Empties the profile: at rest at `(p, v, a)` from time 0 (segments are overwritten, not
    /// cleared).
    #[inline]
    pub(crate) fn reset(&mut self, p: f64, v: f64, a: f64) {
        self.len = 0;
        self.brake_end = 0.0;
        self.duration = 0.0;
        self.end = [p, v, a];
    }

    /// Appends `t` seconds of jerk `j` from the current end state.
    #[inline]
    pub(crate) fn push_jerk(&mut self, t: f64, j: f64) {
        if !(t > 0.0) || self.len == MAX_SEGMENTS {
            return;
        }
        let [p, v, a] = self.end;
        self.segments[self.len] = Segment {
            start: self.duration,
            length: t,
            p,
            v,
            a,
            j,
        };
        self.len += 1;
        self.end = [
            p + t * (v + t * (0.5 * a + t * j * (1.0 / 6.0))),
            v + t * (a + 0.5 * t * j),
            a + t * j,
        ];
        self.duration += t;
    }

    /// Appends `t` seconds of constant acceleration `a` (the acceleration jumps to it).
    #[inline]
    pub(crate) fn push_acceleration(&mut self, t: f64, a: f64) {
        self.end[2] = a;
        self.push_jerk(t, 0.0);
    }

    /// Appends `t` seconds of constant velocity `v` (velocity jumps to it, zero acceleration).
    #[inline]
    pub(crate) fn push_velocity(&mut self, t: f64, v: f64) {
        self.end[1] = v;
        self.end[2] = 0.0;
        self.push_jerk(t, 0.0);
    }

    /// Marks the end of braking: the main part starts here.
    pub(crate) fn mark_brake_end(&mut self) {
        self.brake_end = self.duration;
    }

    /// Sets the acceleration to `a` unless it is NaN.
    #[inline]
    fn set_hold(&mut self, a: f64) {
        if !a.is_nan() {
            self.end[2] = a;
        }
    }

    /// Sets the velocity to `v` unless it is NaN.
    #[inline]
    fn set_cruise(&mut self, v: f64) {
        if !v.is_nan() {
            self.end[1] = v;
        }
    }

    /// Appends a shape.
    pub(crate) fn push_shape(&mut self, shape: &Shape) {
        for i in 0..7 {
            if shape.t[i] > 0.0 && shape.order == Order::Jerk {
                self.set_hold(shape.hold[i]);
                if i == 3 {
                    self.set_cruise(shape.cruise);
                }
            }
            self.push_value(shape.order, shape.t[i], shape.value[i]);
        }
        self.finish(shape.order, shape.end_v, shape.end_a);
    }

    #[inline]
    fn push_value(&mut self, order: Order, t: f64, value: f64) {
        match order {
            Order::Jerk => self.push_jerk(t, value),
            Order::Acceleration => self.push_acceleration(t, value),
            Order::Velocity => self.push_velocity(t, value),
        }
    }

    #[inline]
    fn finish(&mut self, order: Order, end_v: f64, end_a: f64) {
        match order {
            Order::Jerk => {}
            Order::Acceleration => self.end[2] = end_a,
            Order::Velocity => {
                self.end[1] = end_v;
                self.end[2] = end_a;
            }
        }
    }

    /// Appends `weight · first + (1 − weight) · second` for two shapes of the same order and
    /// duration: the value of each piece between the union of their phase boundaries is the
    /// weighted sum, so every derivative is the weighted sum of the two motions.
    pub(crate) fn push_blend(&mut self, first: &Shape, second: &Shape, weight: f64) {
        let order = first.order;
        let rest = 1.0 - weight;
        let (mut i, mut k) = (0, 0);
        // Time left in the current phase of each shape.
        let (mut left_i, mut left_k) = (first.t[0], second.t[0]);
        while i < 7 && k < 7 {
            if left_i <= 0.0 {
                i += 1;
                if i < 7 {
                    left_i = first.t[i];
                }
                continue;
            }
            if left_k <= 0.0 {
                k += 1;
                if k < 7 {
                    left_k = second.t[k];
                }
                continue;
            }
            let step = if left_i < left_k { left_i } else { left_k };
            let value = weight * first.value[i] + rest * second.value[k];
            if order == Order::Jerk && first.value[i] == 0.0 && second.value[k] == 0.0 {
                // Both hold: the exact blend of their accelerations (and velocities if both
                // cruise).
                self.set_hold(weight * first.hold[i] + rest * second.hold[k]);
                if i == 3 && k == 3 {
                    self.set_cruise(weight * first.cruise + rest * second.cruise);
                }
            }
            self.push_value(order, step, value);
            // The phase that ends here ends exactly (no leftover of rounding).
            if left_i <= left_k {
                left_k -= step;
                left_i = 0.0;
            } else {
                left_i -= step;
                left_k = 0.0;
            }
        }
        // Whatever one shape has left (rounding of equal durations) plays blended with the
        // other's last value.
        while i < 7 {
            if left_i > 0.0 {
                let value = weight * first.value[i] + rest * second.value[6];
                self.push_value(order, left_i, value);
            }
            i += 1;
            if i < 7 {
                left_i = first.t[i];
            }
        }
        while k < 7 {
            if left_k > 0.0 {
                let value = weight * first.value[6] + rest * second.value[k];
                self.push_value(order, left_k, value);
            }
            k += 1;
            if k < 7 {
                left_k = second.t[k];
            }
        }
        self.finish(
            order,
            weight * first.end_v + rest * second.end_v,
            weight * first.end_a + rest * second.end_a,
        );
    }

    /// The largest magnitudes of position, velocity and acceleration at the segment starts and
    /// the end (the scale of the rounding in the end state).
    pub(crate) fn scale(&self) -> [f64; 3] {
        let mut m = self.end.map(f64::abs);
        for s in &self.segments[..self.len] {
            m[0] = f64::max(m[0], s.p.abs());
            m[1] = f64::max(m[1], s.v.abs());
            m[2] = f64::max(m[2], s.a.abs());
        }
        m
    }

    /// Duration of the profile in seconds (the axis then continues from its end state with
    /// constant acceleration).
    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// Duration of the braking that brings a start beyond the limits back within them.
    pub fn braking_duration(&self) -> f64 {
        self.brake_end
    }

    /// The segment containing `t` (`len` for after the end), searched from `hint`.
    #[inline(always)]
    pub(crate) fn find(&self, t: f64, hint: usize) -> usize {
        let mut i = if hint < self.len { hint } else { 0 };
        if t >= self.duration {
            return self.len;
        }
        while i > 0 && t < self.segments[i].start {
            i -= 1;
        }
        while i + 1 < self.len && t >= self.segments[i + 1].start {
            i += 1;
        }
        i
    }

    /// `(p, v, a, j)` at `t` in segment `index` (as [`Self::find`] returns).
    #[inline(always)]
    pub(crate) fn at_index(&self, t: f64, index: usize) -> [f64; 4] {
        if index >= self.len {
            let tau = t - self.duration;
            let [p, v, a] = self.end;
            return [p + tau * (v + 0.5 * tau * a), v + tau * a, a, 0.0];
        }
        let s = &self.segments[index];
        // Before the start, hold the start state.
        let tau = t - s.start;
        if tau < 0.0 {
            return [s.p, s.v, s.a, s.j];
        }
        s.at(if tau < s.length { tau } else { s.length })
    }

    /// `(p, v, a, j)` at time `t` (before 0: the start state).
    pub fn at(&self, t: f64) -> [f64; 4] {
        let i = self.find(t, 0);
        self.at_index(t, i)
    }

    /// The smallest and largest position on `[0, duration]` and when they occur
    /// (`[min, max, t_min, t_max]`): at segment ends and where the velocity crosses zero.
    pub fn position_extrema(&self) -> [f64; 4] {
        let [p_end, ..] = self.end;
        let mut ext = [p_end, p_end, self.duration, self.duration];
        let mut note = |p: f64, t: f64| {
            if p < ext[0] {
                ext[0] = p;
                ext[2] = t;
            }
            if p > ext[1] {
                ext[1] = p;
                ext[3] = t;
            }
        };
        for s in &self.segments[..self.len] {
            let length = s.length;
            note(s.p, s.start);
            // v(τ) = v + a τ + j τ²/2 = 0 inside the segment.
            let mut roots = [0.0; 2];
            let n = super::roots::quadratic(0.5 * s.j, s.a, s.v, &mut roots);
            for &tau in &roots[..n] {
                if tau > 0.0 && tau < length {
                    note(s.at(tau)[0], s.start + tau);
                }
            }
        }
        ext
    }
}
