//! The page's interface: one [`View`] behind `extern "C"` functions of plain numbers (`f32`,
//! `i32`, `u32`), so JavaScript calls them straight from `WebAssembly.instantiate` with no
//! binding generator and no shared memory to manage.
//!
//! Legs and servos are numbered 1..=6, as users see them; lengths in mm, pulses in us, angles
//! in degrees. A number asked of something that does not exist (a leg out of range, a geometry
//! not built yet) is NaN. WebAssembly runs one thread: the `View` lives in a thread-local.

use core::cell::{Cell, RefCell};

use kinematics_core::{Direction, GeometryError, Leg, ServoConfig, Vec3, LEGS};

#[cfg(doc)]
use crate::Status;
use crate::{BuildError, View};

std::thread_local! {
    static VIEW: RefCell<View> = RefCell::new(View::new());
    /// The leg the last build error names (1..=6), 0 if none.
    static ERROR_LEG: Cell<u8> = const { Cell::new(0) };
}

fn with_view<T>(f: impl FnOnce(&mut View) -> T) -> T {
    VIEW.with(|view| f(&mut view.borrow_mut()))
}

/// Index 0..=5 of leg or servo number 1..=6.
fn index(number: u32) -> Option<usize> {
    let i = (number as usize).checked_sub(1)?;
    (i < LEGS).then_some(i)
}

/// Stages leg `leg`'s build coordinates as `geometry` lists them: shaft centre `b` and platform
/// joint `p` (mm), arm-plane angle `beta` (deg). Returns 0, or -1 for a leg out of range.
#[no_mangle]
pub extern "C" fn view_set_leg(
    leg: u32,
    bx_mm: f32,
    by_mm: f32,
    bz_mm: f32,
    px_mm: f32,
    py_mm: f32,
    pz_mm: f32,
    beta_deg: f32,
) -> i32 {
    let Some(i) = index(leg) else {
        return -1;
    };
    let staged = Leg {
        base_mm: Vec3::new(bx_mm, by_mm, bz_mm),
        platform_mm: Vec3::new(px_mm, py_mm, pz_mm),
        beta_rad: beta_deg.to_radians(),
    };
    with_view(|view| view.set_leg(i, staged));
    0
}

/// Builds the geometry from the staged legs, arm length `a` and rod length `s` (mm). Returns 0,
/// or why not: 1 a leg is missing, 2 a coordinate is not finite, 3 a length is not positive,
/// 4 no home height (eq. 10), 5 the legs' home heights disagree, 6 home unreachable (eq. 9);
/// [`view_error_leg`] names the leg.
#[no_mangle]
pub extern "C" fn view_build(arm_mm: f32, rod_mm: f32) -> i32 {
    let result = with_view(|view| view.build(arm_mm, rod_mm));
    let (code, leg) = match result {
        Ok(()) => (0, 0),
        Err(BuildError::MissingLeg { leg }) => (1, leg),
        Err(BuildError::Geometry(e)) => match e {
            GeometryError::NonFiniteLeg { leg } => (2, leg),
            GeometryError::BadLength { .. } => (3, 0),
            GeometryError::NoHomeHeight { leg } => (4, leg),
            GeometryError::LegsDisagree { leg, .. } => (5, leg),
            GeometryError::HomeUnreachable { leg } => (6, leg),
        },
    };
    ERROR_LEG.with(|l| l.set(leg));
    code
}

/// The leg the last [`view_build`] error names (1..=6), 0 if none.
#[no_mangle]
pub extern "C" fn view_error_leg() -> u32 {
    ERROR_LEG.with(|l| l.get().into())
}

/// Home height `h0` of the built geometry (eq. 10), mm; NaN without one.
#[no_mangle]
pub extern "C" fn view_home_height_mm() -> f32 {
    with_view(|view| {
        view.solver()
            .map_or(f32::NAN, |s| s.geometry().home_height_mm())
    })
}

/// Home arm angle `alpha0` of leg `leg` (eq. 12) as the core derives it from the geometry, deg;
/// NaN without one.
#[no_mangle]
pub extern "C" fn view_alpha0_deg(leg: u32) -> f32 {
    with_view(|view| match (view.solver(), index(leg)) {
        (Some(solver), Some(i)) => solver.alpha0_rad(i).to_degrees(),
        _ => f32::NAN,
    })
}

/// Sets servo `servo`'s mapping as `config` lists it: home pulse (trim), rate (us/rad),
/// direction (`dir` > 0 normal, < 0 reversed) and limits (us). Returns 0, -1 for a servo out of
/// range or a direction of 0, -2 for numbers the core refuses (then the servo is unknown).
#[no_mangle]
pub extern "C" fn view_set_servo(
    servo: u32,
    trim_us: f32,
    rate_us_rad: f32,
    dir: i32,
    min_us: f32,
    max_us: f32,
) -> i32 {
    let (Some(i), Some(direction)) = (index(servo), direction(dir)) else {
        return -1;
    };
    let config = ServoConfig {
        home_us: trim_us,
        rate_us_per_rad: rate_us_rad,
        direction,
        min_us,
        max_us,
    };
    if with_view(|view| view.set_servo(i, config)) {
        0
    } else {
        -2
    }
}

fn direction(dir: i32) -> Option<Direction> {
    match dir.signum() {
        1 => Some(Direction::Normal),
        -1 => Some(Direction::Reversed),
        _ => None,
    }
}

/// Solves for six pulse widths (us, servo 1 first). Returns the [`Status`]: 0 solved, 1 no
/// geometry, 2 servo settings missing, 3 no solution, 4 a pulse is not finite.
#[no_mangle]
pub extern "C" fn view_solve(w1: f32, w2: f32, w3: f32, w4: f32, w5: f32, w6: f32) -> i32 {
    with_view(|view| view.solve([w1, w2, w3, w4, w5, w6])) as i32
}

/// Arm angle `alpha` of leg `leg` the last pulses command, deg (NaN if unknown).
#[no_mangle]
pub extern "C" fn view_arm_deg(leg: u32) -> f32 {
    with_view(|view| index(leg).map_or(f32::NAN, |i| view.frame().arm_rad[i].to_degrees()))
}

/// Coordinate `axis` of the last pose found: 0..=2 x, y, z in mm (z from the home height),
/// 3..=5 roll, pitch, yaw in deg (eq. 1's order); home before the first. After a
/// [`Status::NoSolution`] it is still the last pose found, which the page shows as such.
#[no_mangle]
pub extern "C" fn view_pose(axis: u32) -> f32 {
    with_view(|view| {
        let p = view.frame().pose.to_array();
        match axis {
            0..=2 => p[axis as usize],
            3..=5 => p[axis as usize].to_degrees(),
            _ => f32::NAN,
        }
    })
}

/// Newton iterations of the last solve.
#[no_mangle]
pub extern "C" fn view_iterations() -> u32 {
    with_view(|view| view.frame().iterations.into())
}

/// How well the rods close at the last pose found: the largest `| |q_i - A_i| - s |`, mm.
#[no_mangle]
pub extern "C" fn view_rod_error_mm() -> f32 {
    with_view(|view| view.frame().rod_error_mm)
}

/// Coordinate `axis` (0 x, 1 y, 2 z) of servo `leg`'s shaft centre `b_i`, base frame, mm.
#[no_mangle]
pub extern "C" fn view_base_mm(leg: u32, axis: u32) -> f32 {
    with_view(|view| match (view.solver(), index(leg)) {
        (Some(solver), Some(i)) => component(&solver.geometry().leg(i).base_mm, axis),
        _ => f32::NAN,
    })
}

/// Coordinate `axis` of leg `leg`'s arm tip `A_i` at the last pulses (eq. 4-6), base frame, mm.
#[no_mangle]
pub extern "C" fn view_tip_mm(leg: u32, axis: u32) -> f32 {
    with_view(|view| index(leg).map_or(f32::NAN, |i| component(&view.frame().tips_mm[i], axis)))
}

/// Coordinate `axis` of leg `leg`'s platform joint `q_i` at the last pose found (eq. 2), base
/// frame, mm.
#[no_mangle]
pub extern "C" fn view_joint_mm(leg: u32, axis: u32) -> f32 {
    with_view(|view| index(leg).map_or(f32::NAN, |i| component(&view.frame().joints_mm[i], axis)))
}

/// Sets the pivot (`config`'s `pivot_x_mm`, `pivot_y_mm`, `pivot_z_mm`: the rotation centre,
/// platform frame, mm). Returns 0, or -1 if the core refuses it (nothing changes).
#[no_mangle]
pub extern "C" fn view_set_pivot(x_mm: f32, y_mm: f32, z_mm: f32) -> i32 {
    if with_view(|view| view.set_pivot(Vec3::new(x_mm, y_mm, z_mm))) {
        0
    } else {
        -1
    }
}

/// Coordinate `axis` of the platform frame's origin at the last pose found, base frame, mm
/// (with a pivot, not `(x, y, h0 + z)`: see [`crate::Frame::origin_mm`]).
#[no_mangle]
pub extern "C" fn view_origin_mm(axis: u32) -> f32 {
    with_view(|view| component(&view.frame().origin_mm, axis))
}

fn component(v: &Vec3, axis: u32) -> f32 {
    match axis {
        0..=2 => v[axis as usize],
        _ => f32::NAN,
    }
}
