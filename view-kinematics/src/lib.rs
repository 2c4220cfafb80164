//! The browser view's kinematics, compiled to WebAssembly: from the six pulse widths measured on
//! the emulated pins to what a real platform would do with them, using this project's own
//! `kinematics-core`, and the points the page draws.
//!
//! Data flows one way, as on a real platform:
//!
//! pulse widths `W_i` (us) -> arm angles `alpha_i` (the inverse of eq. 13, 14 of "The
//! Mathematics of the Stewart Platform", with the servo settings the firmware lists in `config`)
//! -> platform pose (the core's forward kinematics, Newton's method from the previous pose) ->
//! arm tips (eq. 4-6) and platform joints (eq. 2) to draw.
//!
//! The geometry is the one the firmware lists in `geometry` (each leg's `b_i`, `p_i`, `beta_i`,
//! the arm and rod lengths), rebuilt here with the core, turning about the pivot `config` lists
//! (`pivot_x_mm` ..., the firmware's rotation centre: the pose found is in the convention of
//! the poses the board is sent). Nothing is taken from what the firmware intended (its target
//! or its own arm angles): only the pins.
//!
//! Units: mm, us; radians inside, degrees for what the page shows. [`View`] is the Rust API
//! (tested on the host); [`exports`] wraps one `View` in `extern "C"` functions of plain numbers,
//! which the page calls without any binding generator.

use kinematics_core::forward::{self, Options};
use kinematics_core::legs::ArmState;
use kinematics_core::{
    Geometry, GeometryError, Leg, Libm, Pose, ServoConfig, ServoSet, Solver, Vec3, LEGS,
};

pub mod exports;

/// What [`View::solve`] found for one set of pulses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(i32)]
pub enum Status {
    /// The forward kinematics found the pose.
    Solved = 0,
    /// No geometry yet (the firmware's `geometry` listing has not been seen).
    NoGeometry = 1,
    /// Not every servo's mapping is known yet (the firmware's `config` listing).
    NoServos = 2,
    /// These arm angles put the platform nowhere: the forward kinematics has no solution near
    /// the last pose (or home), or did not converge. Drawn as such.
    NoSolution = 3,
    /// A pulse width is not a finite number (a pin without pulses).
    BadPulse = 4,
}

/// Why [`View::build`] made no geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BuildError {
    /// Leg `leg` (1..=6) was never given.
    MissingLeg {
        /// Leg number, 1..=6.
        leg: u8,
    },
    /// The core refused the build numbers.
    Geometry(GeometryError),
}

/// The last solve: arm angles always (they come straight from the pulses), the pose and the
/// points of the last pose found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// The outcome of the last solve.
    pub status: Status,
    /// Arm angles `alpha_i` the pulses command, rad (NaN before the first solve with servos).
    pub arm_rad: [f32; LEGS],
    /// The pose found, or the last one found before a [`Status::NoSolution`] (mm from home, rad).
    pub pose: Pose,
    /// Arm tips `A_i` at `arm_rad` (eq. 4-6), base frame, mm.
    pub tips_mm: [Vec3; LEGS],
    /// Platform joints `q_i` at `pose` (eq. 2), base frame, mm.
    pub joints_mm: [Vec3; LEGS],
    /// The platform frame's origin at `pose`, base frame, mm: `(x, y, h0 + z) + c - R c` with
    /// `c` the pivot (where the page places the plate).
    pub origin_mm: Vec3,
    /// Newton iterations of the last solve (0 if it did not run).
    pub iterations: u8,
    /// Largest `| |q_i - A_i| - s |` at the pose found: how well the rods close, mm.
    pub rod_error_mm: f32,
}

/// Newton's options for the view: the core's defaults with more iterations, so that a jump of
/// the pins (a move with the speed limits off) is followed in one solve.
pub fn forward_options() -> Options {
    Options {
        max_iterations: 40,
        ..Options::default()
    }
}

/// The view's state: the geometry and servo settings the firmware reported, and the last solve.
#[derive(Debug, Clone)]
pub struct View {
    legs: [Option<Leg>; LEGS],
    solver: Option<Solver>,
    servos: [Option<ServoConfig>; LEGS],
    /// The pivot (the IK's rotation centre), platform frame, mm, as `config` lists it.
    pivot_mm: Vec3,
    /// Where the last solve ended; the next one starts there (the forward kinematics has
    /// several solutions: the one nearest the last pose is the platform's continuous motion).
    last_pose: Option<Pose>,
    frame: Frame,
}

impl Default for View {
    fn default() -> View {
        View::new()
    }
}

impl View {
    /// A view that knows nothing yet.
    pub fn new() -> View {
        View {
            legs: [None; LEGS],
            solver: None,
            servos: [None; LEGS],
            pivot_mm: Vec3::zeros(),
            last_pose: None,
            frame: Frame {
                status: Status::NoGeometry,
                arm_rad: [f32::NAN; LEGS],
                pose: Pose::HOME,
                tips_mm: [Vec3::zeros(); LEGS],
                joints_mm: [Vec3::zeros(); LEGS],
                origin_mm: Vec3::zeros(),
                iterations: 0,
                rod_error_mm: f32::NAN,
            },
        }
    }

    /// Stages leg `index`'s (0..=5) build coordinates, as `geometry` lists them; takes effect
    /// at the next [`View::build`]. Returns false for an index out of range.
    pub fn set_leg(&mut self, index: usize, leg: Leg) -> bool {
        match self.legs.get_mut(index) {
            Some(slot) => {
                *slot = Some(leg);
                true
            }
            None => false,
        }
    }

    /// Builds the geometry from the staged legs and the arm and rod lengths, mm. On success the
    /// next solve starts from home; on failure the view has no geometry.
    pub fn build(&mut self, arm_mm: f32, rod_mm: f32) -> Result<(), BuildError> {
        self.solver = None;
        self.last_pose = None;
        let mut legs = [Leg {
            base_mm: Vec3::zeros(),
            platform_mm: Vec3::zeros(),
            beta_rad: 0.0,
        }; LEGS];
        for (i, (out, staged)) in legs.iter_mut().zip(&self.legs).enumerate() {
            *out = staged.ok_or(BuildError::MissingLeg { leg: i as u8 + 1 })?;
        }
        let geometry = Geometry::new(legs, arm_mm, rod_mm).map_err(BuildError::Geometry)?;
        let mut solver = Solver::new(geometry).map_err(BuildError::Geometry)?;
        // (A pivot the core refuses was refused by `set_pivot`: never stored.)
        let _ = solver.set_rotation_centre_mm(self.pivot_mm);
        self.solver = Some(solver);
        Ok(())
    }

    /// Sets the pivot (the rotation centre poses turn about), platform frame, mm, as `config`
    /// lists it: the geometry (if built) turns about it from the next solve, which starts from
    /// home. Refused (false, nothing changes) if the core refuses it (not finite, too far).
    pub fn set_pivot(&mut self, pivot_mm: Vec3) -> bool {
        if kinematics_core::configuration::check_centre(pivot_mm).is_err() {
            return false;
        }
        if pivot_mm != self.pivot_mm {
            self.pivot_mm = pivot_mm;
            self.last_pose = None;
            if let Some(solver) = &mut self.solver {
                let _ = solver.set_rotation_centre_mm(pivot_mm);
            }
        }
        true
    }

    /// The geometry's solver, once built.
    pub fn solver(&self) -> Option<&Solver> {
        self.solver.as_ref()
    }

    /// Sets servo `index`'s (0..=5) mapping, as `config` lists it. Refused (false) for an index
    /// out of range or numbers the core does not accept (then that servo is unknown).
    pub fn set_servo(&mut self, index: usize, servo: ServoConfig) -> bool {
        let Some(slot) = self.servos.get_mut(index) else {
            return false;
        };
        let valid = servo.validate(index as u8 + 1).is_ok();
        *slot = valid.then_some(servo);
        valid
    }

    /// The last solve.
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// Arm angles and pose for six pulse widths, us (servo `i + 1` at index `i`).
    pub fn solve(&mut self, pulse_us: [f32; LEGS]) -> Status {
        self.frame.iterations = 0;
        self.frame.status = self.solve_inner(pulse_us);
        self.frame.status
    }

    fn solve_inner(&mut self, pulse_us: [f32; LEGS]) -> Status {
        let Some(solver) = &self.solver else {
            return Status::NoGeometry;
        };
        let mut servos = ServoSet::default();
        for (out, known) in servos.0.iter_mut().zip(&self.servos) {
            match known {
                Some(servo) => *out = *servo,
                None => return Status::NoServos,
            }
        }
        // The inverse of eq. 13, 14: alpha_i = alpha0_i + (W_i - W0_i) / (+-r_i).
        let Ok(arm_rad) = forward::arm_angles_for_pulses(solver, &servos, &pulse_us) else {
            self.frame.arm_rad = [f32::NAN; LEGS];
            return Status::BadPulse;
        };
        self.frame.arm_rad = arm_rad;
        let last = self.last_pose.unwrap_or(Pose::HOME);
        self.frame.tips_mm = ArmState::at_angles::<Libm>(solver, &last, arm_rad).tips_mm;

        let mut outcome = forward::arms::<Libm>(solver, &arm_rad, &last, forward_options());
        if outcome.is_err() && self.last_pose.is_some() {
            // Far from the last pose (or that branch ended): try again from home.
            outcome = forward::arms::<Libm>(solver, &arm_rad, &Pose::HOME, forward_options());
        }
        let found = match outcome {
            Ok(found) => found,
            Err(_) => return Status::NoSolution,
        };
        let state = ArmState::at_angles::<Libm>(solver, &found.pose, arm_rad);
        let rod_mm = solver.geometry().rod_mm();
        self.frame.pose = found.pose;
        self.frame.joints_mm = state.placement.joints_mm;
        let p = &state.placement;
        self.frame.origin_mm = p.centre_mm - p.rotation * solver.rotation_centre_mm();
        self.frame.iterations = found.iterations;
        self.frame.rod_error_mm = state
            .rods_mm
            .iter()
            .map(|rod| (rod.norm() - rod_mm).abs())
            .fold(0.0, f32::max);
        self.last_pose = Some(found.pose);
        Status::Solved
    }
}

#[cfg(test)]
mod tests;
