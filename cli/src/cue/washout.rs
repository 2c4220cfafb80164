//! The classical washout filter (Reid and Nahon, "Flight simulation motion-base drive
//! algorithms", UTIAS report 296, 1985; Conrad and Schmidt, NASA CR-1601, 1970): an aircraft's
//! specific force and angular rates at the pilot's head in, a platform pose out.
//!
//! - **Translation**: the scaled specific force (minus gravity's 1 g in heave), high-pass
//!   filtered (2nd order, or 3rd so that a sustained acceleration leaves no offset) and
//!   integrated twice: `x(s) = HP(s) / s^2 * k f(s)`.
//! - **Tilt coordination**: the scaled specific force low-pass filtered becomes a sustained
//!   tilt, so that gravity along the tilted seat is felt as that force (`pitch = -asin(f_x/g)`,
//!   `roll = asin(f_y / (g cos pitch))`, exact for the pose's `Rz Ry Rx`), its rate limited
//!   below what a pilot perceives as a rotation.
//! - **Rotation**: the scaled angular rates, high-pass filtered and integrated once:
//!   `angle(s) = HP(s) / s * k w(s)`, plus the tilt (roll and pitch). Body rates are taken as
//!   the platform's Euler-angle rates (the angles stay small).
//!
//! Each channel is one rational transfer function of order at most 3, realised in controllable
//! canonical form and stepped with the trapezoidal rule (Tustin's bilinear transform) at the
//! telemetry's own time step, which may change from sample to sample. A channel starts in the
//! steady state of its first input, so the first sample moves nothing.
//!
//! Frames: the aircraft's body axes (x forward, y right, z down; p, q, r about them) are turned
//! into the platform's (x forward, y left, z up; roll, pitch, yaw about them, as the board's
//! `pose` takes them) by flipping y and z; each axis' `sign` then flips that axis of the
//! platform's motion. Units: specific force m/s^2, rates rad/s, translation m inside and mm
//! out, angles rad inside and degrees out.

use kinematics_core::pose::Axis;

/// Standard gravity, m/s^2.
pub const G: f64 = 9.80665;

/// A polynomial in s, highest power first.
pub type Polynomial = Vec<f64>;

/// The product of two polynomials.
pub fn multiply(a: &[f64], b: &[f64]) -> Polynomial {
    let mut out = vec![0.0; a.len() + b.len() - 1];
    for (i, x) in a.iter().enumerate() {
        for (j, y) in b.iter().enumerate() {
            out[i + j] += x * y;
        }
    }
    out
}

/// A continuous-time transfer function `num(s) / den(s)`, proper (`num` no longer than `den`).
#[derive(Debug, Clone, PartialEq)]
pub struct TransferFunction {
    /// Numerator, highest power first.
    pub num: Polynomial,
    /// Denominator, highest power first, leading coefficient not 0.
    pub den: Polynomial,
}

impl TransferFunction {
    /// The 2nd-order section `s^2 + 2 zeta w s + w^2`.
    pub fn quadratic(w: f64, zeta: f64) -> Polynomial {
        vec![1.0, 2.0 * zeta * w, w * w]
    }

    /// A high-pass filter of order 1 (`s / (s + w)`), 2 (`s^2 / (s^2 + 2 zeta w s + w^2)`) or
    /// 3 (the 2nd-order one times `s / (s + w3)`), divided by `s^integrations`.
    pub fn high_pass_integrated(
        order: u8,
        w: f64,
        zeta: f64,
        w3: f64,
        integrations: u8,
    ) -> TransferFunction {
        let den = match order {
            1 => vec![1.0, w],
            2 => TransferFunction::quadratic(w, zeta),
            _ => multiply(&TransferFunction::quadratic(w, zeta), &[1.0, w3]),
        };
        // s^order / s^integrations = s^(order - integrations): the caller keeps order >= it.
        let mut num = vec![1.0];
        num.extend(std::iter::repeat_n(
            0.0,
            usize::from(order.saturating_sub(integrations)),
        ));
        TransferFunction { num, den }
    }

    /// A low-pass filter of order 1 (`w / (s + w)`) or 2 (`w^2 / (s^2 + 2 zeta w s + w^2)`).
    pub fn low_pass(order: u8, w: f64, zeta: f64) -> TransferFunction {
        match order {
            1 => TransferFunction {
                num: vec![w],
                den: vec![1.0, w],
            },
            _ => TransferFunction {
                num: vec![w * w],
                den: TransferFunction::quadratic(w, zeta),
            },
        }
    }
}

/// A transfer function's state-space realisation and state, stepped by the trapezoidal rule.
#[derive(Debug, Clone, PartialEq)]
pub struct Filter {
    /// `den` made monic, without its leading 1: `a[k]` multiplies `s^(n-1-k)`.
    a: Vec<f64>,
    /// The strictly proper numerator's coefficients, same order.
    c: Vec<f64>,
    /// Direct feed-through.
    d: f64,
    /// State (controllable canonical: `x[0]` the lowest derivative).
    x: Vec<f64>,
    /// The last input.
    u: f64,
    /// Whether a first input has set the state.
    started: bool,
}

impl Filter {
    /// The realisation of a proper transfer function, at rest.
    pub fn new(tf: &TransferFunction) -> Filter {
        let lead = tf.den[0];
        let n = tf.den.len() - 1;
        let a: Vec<f64> = tf.den[1..].iter().map(|v| v / lead).collect();
        // Numerator padded to n + 1 coefficients.
        let mut b = vec![0.0; n + 1 - tf.num.len().min(n + 1)];
        b.extend(tf.num.iter().map(|v| v / lead));
        let d = b[0];
        let c = (0..n).map(|k| b[k + 1] - d * a[k]).collect();
        Filter {
            a,
            c,
            d,
            x: vec![0.0; n],
            u: 0.0,
            started: false,
        }
    }

    fn n(&self) -> usize {
        self.a.len()
    }

    /// `A x + B u`: controllable canonical, `x[i]' = x[i+1]`, `x[n-1]' = u - sum a x`.
    fn derivative(&self, x: &[f64], u: f64) -> Vec<f64> {
        let n = self.n();
        let mut dx = vec![0.0; n];
        dx[..n - 1].copy_from_slice(&x[1..]);
        dx[n - 1] = u - (0..n).map(|k| self.a[n - 1 - k] * x[k]).sum::<f64>();
        dx
    }

    fn output(&self, u: f64) -> f64 {
        let n = self.n();
        (0..n).map(|k| self.c[n - 1 - k] * self.x[k]).sum::<f64>() + self.d * u
    }

    /// Puts the filter in the steady state of a constant input `u` (the output that input
    /// gives for ever); returns that output.
    pub fn settle(&mut self, u: f64) -> f64 {
        let n = self.n();
        self.x = vec![0.0; n];
        // A x = -B u: x[1..] = 0, a_0 x[0] = u (a_0: den's constant term). With a_0 = 0 (a
        // pure integrator) there is no steady state: start at rest.
        let a0 = self.a[n - 1];
        if a0 != 0.0 {
            self.x[0] = u / a0;
        }
        self.u = u;
        self.started = true;
        self.output(u)
    }

    /// Advances `dt_s` to input `u`; returns the output. The first input settles the filter.
    pub fn step(&mut self, u: f64, dt_s: f64) -> f64 {
        if !self.started {
            return self.settle(u);
        }
        let n = self.n();
        let h = dt_s / 2.0;
        // (I - h A) x+ = x + h (A x + B u) + h B u+.
        let mut rhs = self.derivative(&self.x, self.u);
        for (r, x) in rhs.iter_mut().zip(&self.x) {
            *r = x + h * *r;
        }
        rhs[n - 1] += h * u;
        let mut m = vec![vec![0.0; n]; n];
        for (i, row) in m.iter_mut().enumerate() {
            row[i] = 1.0;
            if i + 1 < n {
                row[i + 1] = -h;
            }
        }
        for (k, m) in m[n - 1].iter_mut().enumerate() {
            *m += h * self.a[n - 1 - k];
        }
        self.x = solve(m, rhs);
        self.u = u;
        self.output(u)
    }

    /// The current output (for the last input).
    pub fn value(&self) -> f64 {
        self.output(self.u)
    }
}

/// Solves `m x = rhs` by Gaussian elimination with partial pivoting (`m` is `I - h A`, never
/// singular for a stable `A` and `h > 0`).
fn solve(mut m: Vec<Vec<f64>>, mut rhs: Vec<f64>) -> Vec<f64> {
    let n = rhs.len();
    for col in 0..n {
        let pivot = (col..n)
            .max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))
            .unwrap_or(col);
        m.swap(col, pivot);
        rhs.swap(col, pivot);
        let p = m[col][col];
        let (top, below) = m.split_at_mut(col + 1);
        let pivot_row = &top[col];
        for (row, r) in below.iter_mut().enumerate() {
            let f = r[col] / p;
            for (x, y) in r[col..].iter_mut().zip(&pivot_row[col..]) {
                *x -= f * y;
            }
            rhs[col + 1 + row] -= f * rhs[col];
        }
    }
    let mut x = vec![0.0; n];
    for row in (0..n).rev() {
        let s: f64 = (row + 1..n).map(|k| m[row][k] * x[k]).sum();
        x[row] = (rhs[row] - s) / m[row][row];
    }
    x
}

/// One translation or rotation axis' high-pass channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Channel {
    /// Gain on the aircraft's specific force (translation) or rate (rotation).
    pub scale: f64,
    /// High-pass order: 2 or 3 for a translation, 1 or 2 for a rotation.
    pub order: u8,
    /// The high-pass's break frequency (its 2nd-order section's natural frequency), Hz.
    pub hp_hz: f64,
    /// Its damping ratio.
    pub zeta: f64,
    /// A 3rd-order high-pass' first-order break frequency, Hz.
    pub hp3_hz: f64,
    /// +1, or -1 to reverse the axis.
    pub sign: f64,
}

/// Tilt coordination (roll and pitch from the low-passed lateral and longitudinal force).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tilt {
    /// Gain on the specific force (0: no tilt coordination).
    pub scale: f64,
    /// Low-pass order, 1 or 2.
    pub order: u8,
    /// Its break frequency, Hz.
    pub lp_hz: f64,
    /// Its damping ratio.
    pub zeta: f64,
    /// The most the tilt changes per second, degrees/s (below the rotation a pilot perceives).
    pub rate_deg_s: f64,
    /// The largest tilt, degrees.
    pub max_deg: f64,
}

/// The washout's tuning: per axis ([`Axis::ALL`] order) and the tilt.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tuning {
    /// x, y, z (translations) and roll, pitch, yaw (rotations).
    pub axes: [Channel; 6],
    /// Tilt coordination.
    pub tilt: Tilt,
}

impl Default for Tuning {
    /// For a small servo platform (about +-20 mm, +-12 degrees): motion cues of a light
    /// aircraft's take-off, turns and bumps that fit it, with tilt giving the sustained part.
    fn default() -> Tuning {
        let translation = |scale, hp_hz| Channel {
            scale,
            order: 3,
            hp_hz,
            zeta: 1.0,
            hp3_hz: 0.1,
            sign: 1.0,
        };
        let rotation = |scale| Channel {
            scale,
            order: 2,
            hp_hz: 0.2,
            zeta: 1.0,
            hp3_hz: 0.0,
            sign: 1.0,
        };
        Tuning {
            axes: [
                translation(0.3, 1.0),
                translation(0.3, 1.0),
                translation(0.2, 1.5),
                rotation(0.5),
                rotation(0.5),
                rotation(0.5),
            ],
            tilt: Tilt {
                scale: 0.6,
                order: 2,
                lp_hz: 0.4,
                zeta: 1.0,
                rate_deg_s: 3.0,
                max_deg: 10.0,
            },
        }
    }
}

/// What the aircraft feels at the pilot's head, in its body axes (x forward, y right, z down).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Motion {
    /// Specific force (the non-gravitational acceleration; 1 g up, `-G` in z, at rest), m/s^2.
    pub force: [f64; 3],
    /// Angular rates p, q, r, rad/s.
    pub rates: [f64; 3],
}

impl Motion {
    /// At rest, level.
    pub const REST: Motion = Motion {
        force: [0.0, 0.0, -G],
        rates: [0.0, 0.0, 0.0],
    };

    /// The same in the platform's axes (x forward, y left, z up): y and z flipped.
    pub fn in_platform_axes(&self) -> Motion {
        let [fx, fy, fz] = self.force;
        let [p, q, r] = self.rates;
        Motion {
            force: [fx, -fy, -fz],
            rates: [p, -q, -r],
        }
    }
}

/// The washout's output: a platform pose, mm and degrees, before any limit.
pub type Cue = [f64; 6];

/// The tilt angles (roll, pitch, rad, the pose's `Rz Ry Rx` with yaw 0) at which gravity along
/// the platform is felt as the specific force `(fx, fy)` (platform axes, m/s^2).
pub fn tilt_for(fx: f64, fy: f64) -> (f64, f64) {
    let pitch = -(fx / G).clamp(-1.0, 1.0).asin();
    let roll = (fy / (G * pitch.cos())).clamp(-1.0, 1.0).asin();
    (roll, pitch)
}

/// The classical washout filter at work.
#[derive(Debug, Clone)]
pub struct Washout {
    tuning: Tuning,
    /// The six channels' filters.
    channels: Vec<Filter>,
    /// The tilt's low-pass filters (x and y force).
    tilt_lp: [Filter; 2],
    /// The tilt now (roll, pitch), rad.
    tilt: [f64; 2],
    started: bool,
}

fn hz(f: f64) -> f64 {
    2.0 * std::f64::consts::PI * f
}

impl Washout {
    /// A washout at rest.
    pub fn new(tuning: Tuning) -> Washout {
        let channels = tuning
            .axes
            .iter()
            .enumerate()
            .map(|(i, c)| {
                let integrations = if i < 3 { 2 } else { 1 };
                Filter::new(&TransferFunction::high_pass_integrated(
                    c.order,
                    hz(c.hp_hz),
                    c.zeta,
                    hz(c.hp3_hz),
                    integrations,
                ))
            })
            .collect();
        let t = tuning.tilt;
        let lp = Filter::new(&TransferFunction::low_pass(t.order, hz(t.lp_hz), t.zeta));
        Washout {
            tuning,
            channels,
            tilt_lp: [lp.clone(), lp],
            tilt: [0.0, 0.0],
            started: false,
        }
    }

    /// The tuning.
    pub fn tuning(&self) -> &Tuning {
        &self.tuning
    }

    /// Forgets everything: the next sample starts it again (in its steady state).
    pub fn reset(&mut self) {
        *self = Washout::new(self.tuning);
    }

    /// The cue for the next sample, `dt_s` after the previous one (ignored for the first).
    pub fn step(&mut self, motion: &Motion, dt_s: f64) -> Cue {
        let m = motion.in_platform_axes();
        let t = self.tuning.tilt;
        let mut cue = [0.0; 6];
        for (i, (filter, c)) in self.channels.iter_mut().zip(&self.tuning.axes).enumerate() {
            let input = if i < 3 {
                // Heave: the 1 g of rest is no motion.
                let f = if i == 2 { m.force[2] - G } else { m.force[i] };
                c.scale * f
            } else {
                c.scale * m.rates[i - 3]
            };
            let y = filter.step(input, dt_s);
            cue[i] = if i < 3 { y * 1e3 } else { y.to_degrees() };
        }
        // Tilt coordination: the low-passed force's tilt, approached at a limited rate.
        let fx = self.tilt_lp[0].step(t.scale * m.force[0], dt_s);
        let fy = self.tilt_lp[1].step(t.scale * m.force[1], dt_s);
        let (roll, pitch) = tilt_for(fx, fy);
        let max = t.max_deg.to_radians();
        let want = [roll.clamp(-max, max), pitch.clamp(-max, max)];
        if self.started {
            let most = t.rate_deg_s.to_radians() * dt_s.max(0.0);
            for (now, want) in self.tilt.iter_mut().zip(want) {
                *now += (want - *now).clamp(-most, most);
            }
        } else {
            // The first sample: the tilt starts at level and eases to its target.
            self.started = true;
        }
        cue[Axis::Roll as usize] += self.tilt[0].to_degrees();
        cue[Axis::Pitch as usize] += self.tilt[1].to_degrees();
        for (value, c) in cue.iter_mut().zip(&self.tuning.axes) {
            *value *= c.sign;
        }
        cue
    }
}

/// A soft limit: `u` as it is up to `knee * limit`, then bending smoothly (continuous in value
/// and slope) towards `limit`, never reaching it.
pub fn soft_limit(u: f64, limit: f64, knee: f64) -> f64 {
    let start = knee * limit;
    let room = limit - start;
    if u.abs() <= start || room <= 0.0 {
        return u.clamp(-limit, limit);
    }
    u.signum() * (start + room * ((u.abs() - start) / room).tanh())
}

#[cfg(test)]
mod tests {
    //! Each response is compared with its closed form (inverse Laplace transforms worked out
    //! by hand, or `H(jw)` written out for the filter's definition), never with the code.

    use super::*;
    use std::f64::consts::PI;

    /// Runs a filter from rest (settled at 0) with input `u(t)` at steps `dt(k)`; the outputs
    /// with their times.
    fn run(
        tf: &TransferFunction,
        until_s: f64,
        dt: impl Fn(usize) -> f64,
        u: impl Fn(f64) -> f64,
    ) -> Vec<(f64, f64)> {
        let mut filter = Filter::new(tf);
        filter.settle(0.0);
        let mut t = 0.0;
        let mut out = Vec::new();
        let mut k = 0;
        while t < until_s {
            let h = dt(k);
            t += h;
            out.push((t, filter.step(u(t), h)));
            k += 1;
        }
        out
    }

    /// A unit step from rest, at 1 ms steps.
    fn unit_step(tf: &TransferFunction, until_s: f64) -> Vec<(f64, f64)> {
        run(tf, until_s, |_| 1e-3, |_| 1.0)
    }

    fn worst(out: &[(f64, f64)], want: impl Fn(f64) -> f64) -> f64 {
        out.iter()
            .map(|&(t, y)| (y - want(t)).abs())
            .fold(0.0, f64::max)
    }

    #[test]
    fn second_order_translation_step_is_the_damped_oscillator_s() {
        // HP2 / s^2 = 1 / (s^2 + 2 zeta w s + w^2): a unit step of acceleration gives
        // (1 - e^(-zeta w t) (cos wd t + zeta / sqrt(1 - zeta^2) sin wd t)) / w^2.
        let (w, zeta) = (2.0 * PI * 0.7, 0.6);
        let tf = TransferFunction::high_pass_integrated(2, w, zeta, 0.0, 2);
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let want = |t: f64| {
            (1.0 - (-zeta * w * t).exp()
                * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin()))
                / (w * w)
        };
        let out = unit_step(&tf, 6.0);
        // Error of order dt: the trapezoid takes the step as a ramp over the first step.
        assert!(worst(&out, want) < 2e-3 / (w * w), "{}", worst(&out, want));
        // A sustained force leaves the platform displaced by 1 / w^2: why order 3 is the
        // default.
        assert!((out.last().unwrap().1 - 1.0 / (w * w)).abs() < 1e-4);
    }

    /// The third-order translation channel of the next two tests, `a` = 1 Hz, `b` = 0.1 Hz,
    /// zeta = 1, and its unit step response worked out by hand: HP3 / s^2 =
    /// s / ((s + a)^2 (s + b)), so a unit step gives
    /// 1 / ((s + a)^2 (s + b)) = A / (s + b) - A / (s + a) + C / (s + a)^2,
    /// A = 1 / (a - b)^2, C = 1 / (b - a): y = A e^(-bt) - A e^(-at) + C t e^(-at).
    fn third_order_step() -> (TransferFunction, impl Fn(f64) -> f64) {
        let (a, b) = (2.0 * PI * 1.0, 2.0 * PI * 0.1);
        let tf = TransferFunction::high_pass_integrated(3, a, 1.0, b, 2);
        let big_a = 1.0 / ((a - b) * (a - b));
        let c = 1.0 / (b - a);
        let want =
            move |t: f64| big_a * (-b * t).exp() - big_a * (-a * t).exp() + c * t * (-a * t).exp();
        (tf, want)
    }

    /// The largest output's size; asserts that no output is further from `want` than
    /// `tolerance` of it.
    fn assert_within_of_peak(out: &[(f64, f64)], want: impl Fn(f64) -> f64, tolerance: f64) -> f64 {
        let peak = out.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
        assert!(
            worst(out, &want) < tolerance * peak,
            "{} of {peak}",
            worst(out, &want)
        );
        peak
    }

    #[test]
    fn third_order_translation_step_rises_then_washes_back_to_centre() {
        let (tf, want) = third_order_step();
        let out = unit_step(&tf, 40.0);
        let peak = assert_within_of_peak(&out, want, 2e-3);
        assert!(out.last().unwrap().1.abs() < 1e-3 * peak);
    }

    #[test]
    fn a_changing_time_step_gives_the_same_response() {
        // The simulation's steps vary: 0.5 to 2.1 ms here, in a fixed pseudo-random order.
        let (tf, want) = third_order_step();
        let dt = |k: usize| 5e-4 + 1.6e-3 * (((k * 7919) % 101) as f64 / 100.0);
        let out = run(&tf, 10.0, dt, |_| 1.0);
        assert_within_of_peak(&out, want, 4e-3);
    }

    #[test]
    fn rotation_channels_steps() {
        // Order 2: s / (s + w)^2 -> t e^(-wt); order 1: 1 / (s + w) -> (1 - e^(-wt)) / w.
        let w = 2.0 * PI * 0.2;
        let two = unit_step(
            &TransferFunction::high_pass_integrated(2, w, 1.0, 0.0, 1),
            20.0,
        );
        assert!(
            worst(&two, |t| t * (-w * t).exp()) < 1e-3,
            "{}",
            worst(&two, |t| t * (-w * t).exp())
        );
        let one = unit_step(
            &TransferFunction::high_pass_integrated(1, w, 1.0, 0.0, 1),
            20.0,
        );
        let want = |t: f64| (1.0 - (-w * t).exp()) / w;
        assert!(worst(&one, want) < 1e-3, "{}", worst(&one, want));
    }

    /// Complex numbers, just enough for `H(jw)`.
    #[derive(Clone, Copy)]
    struct C(f64, f64);
    impl C {
        fn mul(self, o: C) -> C {
            C(self.0 * o.0 - self.1 * o.1, self.0 * o.1 + self.1 * o.0)
        }
        fn div(self, o: C) -> C {
            let d = o.0 * o.0 + o.1 * o.1;
            C(
                (self.0 * o.0 + self.1 * o.1) / d,
                (self.1 * o.0 - self.0 * o.1) / d,
            )
        }
        fn abs(self) -> f64 {
            self.0.hypot(self.1)
        }
        fn arg(self) -> f64 {
            self.1.atan2(self.0)
        }
    }

    /// Amplitude and phase of a filter's steady response to `sin(2 pi f t)`, by correlation
    /// over whole periods after the transient.
    fn measured(tf: &TransferFunction, f: f64) -> (f64, f64) {
        let dt = 1e-3;
        let period = 1.0 / f;
        let settle = 30.0;
        let periods = 10.0;
        let out = run(
            tf,
            settle + periods * period,
            |_| dt,
            |t| (2.0 * PI * f * t).sin(),
        );
        let (mut s, mut c, mut n) = (0.0, 0.0, 0.0);
        for &(t, y) in out.iter().filter(|p| p.0 > settle) {
            s += y * (2.0 * PI * f * t).sin();
            c += y * (2.0 * PI * f * t).cos();
            n += 1.0;
        }
        let (s, c) = (2.0 * s / n, 2.0 * c / n);
        (s.hypot(c), c.atan2(s))
    }

    /// Asserts a filter's measured response to `sin(2 pi f t)` is `h`: its amplitude within
    /// 1 %, its phase within 0.02 rad.
    fn assert_response(tf: &TransferFunction, f: f64, h: C) {
        let (amp, phase) = measured(tf, f);
        assert!(
            (amp / h.abs() - 1.0).abs() < 0.01,
            "{f} Hz: {amp} vs {}",
            h.abs()
        );
        let dphase = (phase - h.arg() + PI).rem_euclid(2.0 * PI) - PI;
        assert!(dphase.abs() < 0.02, "{f} Hz: phase {phase} vs {}", h.arg());
    }

    #[test]
    fn frequency_responses_match_h_of_jw() {
        let (w0, zeta, wb) = (2.0 * PI * 1.0, 0.8, 2.0 * PI * 0.1);
        for f in [0.05, 0.3, 1.0, 3.0] {
            let jw = C(0.0, 2.0 * PI * f);
            let quad = jw.mul(jw).mul(C(1.0, 0.0));
            let quad = C(quad.0 + w0 * w0, quad.1 + 2.0 * zeta * w0 * jw.1);
            // Translation, order 3: jw / ((jw^2 + 2 zeta w0 jw + w0^2)(jw + wb)).
            let h3 = jw.div(quad.mul(C(wb, jw.1)));
            assert_response(
                &TransferFunction::high_pass_integrated(3, w0, zeta, wb, 2),
                f,
                h3,
            );
            // Tilt low pass, order 2: w0^2 / (jw^2 + 2 zeta w0 jw + w0^2).
            let lp = C(w0 * w0, 0.0).div(quad);
            assert_response(&TransferFunction::low_pass(2, w0, zeta), f, lp);
        }
    }

    #[test]
    fn at_rest_nothing_moves() {
        let mut washout = Washout::new(Tuning::default());
        for _ in 0..500 {
            let cue = washout.step(&Motion::REST, 0.01);
            assert!(cue.iter().all(|v| v.abs() < 1e-9), "{cue:?}");
        }
    }

    #[test]
    fn a_sustained_forward_acceleration_tilts_the_nose_up_at_the_rate_limit() {
        let tuning = Tuning::default();
        let mut washout = Washout::new(tuning);
        washout.step(&Motion::REST, 0.01);
        let a = 2.0; // m/s^2 forward, for ever (a tilt of 7 degrees, below the 10 of max_deg)
        let push = Motion {
            force: [a, 0.0, -G],
            rates: [0.0; 3],
        };
        let dt = 0.01;
        let mut last = 0.0;
        let mut cues = Vec::new();
        for _ in 0..3000 {
            let cue = washout.step(&push, dt);
            let pitch = cue[Axis::Pitch as usize];
            assert!((pitch - last).abs() <= tuning.tilt.rate_deg_s * dt + 1e-9);
            last = pitch;
            cues.push(cue);
        }
        // Nose up: the board's pitch is about y (left), positive lowering +x (the nose).
        let want = -(tuning.tilt.scale * a / G).asin().to_degrees();
        assert!((last - want).abs() < 1e-6, "{last} vs {want}");
        // The surge went forward first, then washed back to centre.
        let most = cues.iter().map(|c| c[0]).fold(f64::MIN, f64::max);
        assert!(most > 1.0, "{most}");
        assert!(cues.last().unwrap()[0].abs() < 0.05 * most);
    }

    #[test]
    fn a_sustained_turn_washes_back_to_level() {
        // A coordinated turn: 1.3 g into the seat, a steady yaw and roll rate.
        let mut washout = Washout::new(Tuning::default());
        washout.step(&Motion::REST, 0.01);
        let turn = Motion {
            force: [0.0, 0.0, -1.3 * G],
            rates: [0.0, 0.02, 0.2],
        };
        let mut most = [0.0f64; 6];
        let mut cue = [0.0; 6];
        for _ in 0..6000 {
            cue = washout.step(&turn, 0.01);
            for (m, c) in most.iter_mut().zip(cue) {
                *m = m.max(c.abs());
            }
        }
        // Heave pressed into the seat went up (the platform rose) and came back; yaw turned
        // (nose right is negative yaw, about z up) and came back.
        assert!(most[2] > 1.0 && most[5] > 1.0, "{most:?}");
        for (i, (c, m)) in cue.iter().zip(most).enumerate() {
            assert!(c.abs() <= 0.02 * m + 1e-9, "axis {i}: {c} of {m}");
        }
    }

    #[test]
    fn signs_reverse_their_axis() {
        let mut tuning = Tuning::default();
        let mut reversed = tuning;
        reversed.axes[0].sign = -1.0;
        reversed.axes[4].sign = -1.0;
        tuning.tilt.scale = 0.5;
        reversed.tilt.scale = 0.5;
        let (mut a, mut b) = (Washout::new(tuning), Washout::new(reversed));
        let push = Motion {
            force: [2.0, 0.0, -G],
            rates: [0.0, 0.1, 0.0],
        };
        a.step(&Motion::REST, 0.01);
        b.step(&Motion::REST, 0.01);
        for _ in 0..100 {
            let (x, y) = (a.step(&push, 0.01), b.step(&push, 0.01));
            assert_eq!(x[0], -y[0]);
            assert_eq!(x[4], -y[4]);
            assert_eq!(x[3], y[3]);
        }
    }

    #[test]
    fn the_tilt_makes_gravity_the_force_asked_for() {
        // Gravity seen in the tilted platform's axes, R^T (0, 0, g), written out for
        // R = Ry(pitch) Rx(roll): g (-sin p, sin r cos p, cos r cos p).
        for (fx, fy) in [(2.0, 0.0), (0.0, -1.5), (1.2, 0.7)] {
            let (r, p) = tilt_for(fx, fy);
            assert!((G * -p.sin() - fx).abs() < 1e-12);
            assert!((G * r.sin() * p.cos() - fy).abs() < 1e-12);
        }
    }

    #[test]
    fn the_soft_limit_is_smooth_bounded_and_plain_below_its_knee() {
        let (limit, knee) = (10.0, 0.6);
        assert_eq!(soft_limit(5.9, limit, knee), 5.9);
        assert_eq!(soft_limit(-5.9, limit, knee), -5.9);
        let mut last = soft_limit(0.0, limit, knee);
        let h = 1e-4;
        for k in 1..200_000 {
            let u = k as f64 * h;
            let y = soft_limit(u, limit, knee);
            assert!(y > last - 1e-12 && y < limit, "{u}: {y}");
            // Slope at most 1 and no jump (continuous at the knee).
            assert!(y - last <= h + 1e-12);
            last = y;
        }
        // At the knee, the slope is still 1.
        let slope = (soft_limit(6.0 + 1e-6, limit, knee) - soft_limit(6.0, limit, knee)) / 1e-6;
        assert!((slope - 1.0).abs() < 1e-5);
        assert!(soft_limit(1e6, limit, knee) <= limit);
    }
}
