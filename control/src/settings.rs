//! Settings: what a user can change without touching code, their names, ranges and defaults.
//!
//! [`Settings`] is the platform: its build numbers (a [`PairedLayout`]), the six servo mappings,
//! the motion limits and the frame rate. `set <name> <value>` changes one value; the controller
//! then validates the whole result ([`Settings::validate`]: every range, the servo set, the
//! geometry) before committing it, so a refused change leaves everything as it was. `defaults`
//! restores [`Settings::default`].
//!
//! Two names `set` takes are not the platform's but a link's ([`LinkSettings`]): `echo` belongs
//! to the link the line came from (each link has its own, see [`crate::session`]) and `baud` is
//! UART0's configuration. `config` lists them with the others; `defaults` leaves them alone, so
//! a host keeps its connection; `save` does not keep them (see [`crate::record`]), so every
//! power-up starts at 115200 baud with echo on, where a terminal finds the board.
//!
//! # Names, meanings, values
//!
//! Each setting's name (as `config` lists it and `set` takes it: [`SettingId`]'s `Display`),
//! its meaning in a few words ([`SettingId::meaning`]) and the form and range of its value
//! ([`SettingId::kind`]) are written once, here; defaults are [`Settings::default`]'s. The
//! user's table of them is `docs/settings.md`, checked against these by
//! `control/tests/documents.rs`.
//!
//! The stream settings are [`crate::stream`]'s, the pins and the e-stop [`crate::safety`]'s,
//! the payload and the torque ratings [`crate::payload`]'s.
//! `servos.<field>` sets that field of all six servos at once. Equation numbers are those of
//! "The Mathematics of the Stewart Platform". The binary form kept in flash is
//! [`crate::record`]'s; the words of every refusal ([`SettingError`]) are [`crate::report`]'s.

use core::fmt::{self, Display, Formatter};

use kinematics_core::geometry::{GeometryError, PairedLayout};
use kinematics_core::ik::Solver;
use kinematics_core::servo::{
    ServoError, MAX_PULSE_US, MAX_RATE_US_PER_RAD, MIN_PULSE_US, MIN_RATE_US_PER_RAD,
};
use kinematics_core::{Direction, Libm, Math, ServoConfig, ServoSet, Vec3, LEGS};

use kinematics_core::pose::Axis;

use crate::number::{parse_f32, parse_u32, NumberError};
use crate::payload::{
    PayloadSettings, MAX_COM_MM, MAX_PAYLOAD_G, MAX_TORQUE_KGCM, MIN_TORQUE_KGCM,
};
use crate::safety::{EstopAction, SafetySettings, FREE_GPIOS};
use crate::servo_speed::{ServoSpeeds, MAX_S_PER_60DEG, MIN_S_PER_60DEG};
use crate::stream::{StreamSettings, TEXT_BITS_MAX, TEXT_BITS_MIN};
use crate::word::{word, Word};

/// Lowest servo frame rate, Hz.
pub const FRAME_HZ_MIN: u16 = 50;
/// Highest servo frame rate, Hz (a 3 ms frame still holds the longest pulse).
pub const FRAME_HZ_MAX: u16 = 333;
/// Baud rates UART0 may be set to, slowest first (the only list of them).
pub const BAUD_RATES: [u32; 8] = [
    9_600, 19_200, 38_400, 57_600, 115_200, 230_400, 460_800, 921_600,
];

/// Default servo frame rate, Hz.
pub const DEFAULT_FRAME_HZ: u16 = 50;
/// Default UART0 baud rate.
pub const DEFAULT_BAUD: u32 = 115_200;
/// Default linear speed limit, mm/s.
pub const DEFAULT_SPEED_MM_S: f32 = 50.0;
/// Default angular speed limit, deg/s.
pub const DEFAULT_SPEED_DEG_S: f32 = 60.0;
/// Farthest the pivot may be from the platform frame's origin along each axis, mm (a driver's
/// head above a seat; within the core's `MAX_CENTRE_MM`).
pub const MAX_PIVOT_MM: f32 = 1000.0;

/// The platform's settings: everything `set` changes except the link settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Settings {
    /// The platform's build numbers.
    pub layout: PairedLayout,
    /// The six servos' pulse mappings and limits (servo `i + 1` at index `i`).
    pub servos: ServoSet,
    /// Linear speed limit, mm/s; 0 = no limit (jump).
    pub speed_mm_s: f32,
    /// Angular speed limit, deg/s; 0 = no limit (jump).
    pub speed_deg_s: f32,
    /// Linear acceleration limit, mm/s^2; 0 = none.
    pub accel_mm_s2: f32,
    /// Angular acceleration limit, deg/s^2; 0 = none.
    pub accel_deg_s2: f32,
    /// Return home after this long without a command, s; 0 = never.
    pub link_timeout_s: f32,
    /// Servo frame rate, Hz.
    pub frame_hz: u16,
    /// How stream frames' counts become poses.
    pub stream: StreamSettings,
    /// The emergency-stop input and the servo-power output.
    pub safety: SafetySettings,
    /// The payload and the servos' torque ratings.
    pub payload: PayloadSettings,
    /// The pivot: the point the platform's rotations turn about (the IK's rotation centre,
    /// [`Solver::set_rotation_centre_mm`]), platform frame, mm: from the platform frame's
    /// origin (the centre of the platform joints' circle), z up. A point of the platform: a
    /// pose's `x y z` is how far it has moved from home, its `roll pitch yaw` turn about it.
    pub pivot_mm: [f32; 3],
    /// The servos' rated speeds.
    pub servo_speed: ServoSpeeds,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            layout: PairedLayout::default(),
            servos: ServoSet::default(),
            speed_mm_s: DEFAULT_SPEED_MM_S,
            speed_deg_s: DEFAULT_SPEED_DEG_S,
            accel_mm_s2: 0.0,
            accel_deg_s2: 0.0,
            link_timeout_s: 0.0,
            frame_hz: DEFAULT_FRAME_HZ,
            stream: StreamSettings::default(),
            safety: SafetySettings::default(),
            payload: PayloadSettings::default(),
            pivot_mm: [0.0; 3],
            servo_speed: ServoSpeeds::default(),
        }
    }
}

/// The link settings `config` lists: UART0's baud rate and the asking link's echo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LinkSettings {
    /// UART0's baud rate.
    pub baud: u32,
    /// Echo typed characters and show a prompt on this link.
    pub echo: bool,
}

impl Default for LinkSettings {
    fn default() -> LinkSettings {
        LinkSettings {
            baud: DEFAULT_BAUD,
            echo: true,
        }
    }
}

impl LinkSettings {
    /// The value of a link setting (`None` for the platform's).
    pub fn get(&self, id: SettingId) -> Option<SettingValue> {
        match id {
            SettingId::Baud => Some(SettingValue::Whole(self.baud)),
            SettingId::Echo => Some(SettingValue::Flag(self.echo)),
            _ => None,
        }
    }
}

/// One of the six build numbers of a [`PairedLayout`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LayoutParam {
    /// `base_radius_mm`.
    BaseRadiusMm,
    /// `base_half_angle_deg`.
    BaseHalfAngleDeg,
    /// `platform_radius_mm`.
    PlatformRadiusMm,
    /// `platform_half_angle_deg`.
    PlatformHalfAngleDeg,
    /// `arm_mm`.
    ArmMm,
    /// `rod_mm`.
    RodMm,
}

impl LayoutParam {
    /// All, in listing order.
    pub const ALL: [LayoutParam; 6] = [
        LayoutParam::BaseRadiusMm,
        LayoutParam::BaseHalfAngleDeg,
        LayoutParam::PlatformRadiusMm,
        LayoutParam::PlatformHalfAngleDeg,
        LayoutParam::ArmMm,
        LayoutParam::RodMm,
    ];

    /// The setting name.
    pub const fn name(self) -> &'static str {
        match self {
            LayoutParam::BaseRadiusMm => "base_radius_mm",
            LayoutParam::BaseHalfAngleDeg => "base_half_angle_deg",
            LayoutParam::PlatformRadiusMm => "platform_radius_mm",
            LayoutParam::PlatformHalfAngleDeg => "platform_half_angle_deg",
            LayoutParam::ArmMm => "arm_mm",
            LayoutParam::RodMm => "rod_mm",
        }
    }

    pub(crate) fn get(self, l: &PairedLayout) -> f32 {
        match self {
            LayoutParam::BaseRadiusMm => l.base_radius_mm,
            LayoutParam::BaseHalfAngleDeg => l.base_half_angle_deg,
            LayoutParam::PlatformRadiusMm => l.platform_radius_mm,
            LayoutParam::PlatformHalfAngleDeg => l.platform_half_angle_deg,
            LayoutParam::ArmMm => l.arm_mm,
            LayoutParam::RodMm => l.rod_mm,
        }
    }

    pub(crate) fn slot(self, l: &mut PairedLayout) -> &mut f32 {
        match self {
            LayoutParam::BaseRadiusMm => &mut l.base_radius_mm,
            LayoutParam::BaseHalfAngleDeg => &mut l.base_half_angle_deg,
            LayoutParam::PlatformRadiusMm => &mut l.platform_radius_mm,
            LayoutParam::PlatformHalfAngleDeg => &mut l.platform_half_angle_deg,
            LayoutParam::ArmMm => &mut l.arm_mm,
            LayoutParam::RodMm => &mut l.rod_mm,
        }
    }
}

/// Which servos a servo setting addresses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServoSel {
    /// Servo number 1..=6.
    One(u8),
    /// All six (`servos.<field>`).
    All,
}

/// One field of a servo's configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ServoParam {
    /// Home pulse `W0`, us.
    TrimUs,
    /// Servo rate `r`, us/rad.
    RateUsRad,
    /// Direction.
    Dir,
    /// Lower pulse limit, us.
    MinUs,
    /// Upper pulse limit, us.
    MaxUs,
    /// Rated torque, kgf cm (a payload setting: [`PayloadSettings::torque_kgcm`]).
    TorqueKgcm,
    /// Rated speed, s per 60 degrees ([`ServoSpeeds::s_per_60deg`]).
    SpeedS60Deg,
}

impl ServoParam {
    /// All, in listing order.
    pub const ALL: [ServoParam; 7] = [
        ServoParam::TrimUs,
        ServoParam::RateUsRad,
        ServoParam::Dir,
        ServoParam::MinUs,
        ServoParam::MaxUs,
        ServoParam::TorqueKgcm,
        ServoParam::SpeedS60Deg,
    ];

    /// The field name after `servoN.`.
    pub const fn name(self) -> &'static str {
        match self {
            ServoParam::TrimUs => "trim_us",
            ServoParam::RateUsRad => "rate_us_rad",
            ServoParam::Dir => "dir",
            ServoParam::MinUs => "min_us",
            ServoParam::MaxUs => "max_us",
            ServoParam::TorqueKgcm => "torque_kgcm",
            ServoParam::SpeedS60Deg => "speed_s_60deg",
        }
    }

    /// True for the fields of the servo's pulse mapping ([`ServoConfig`]): changing them moves
    /// the pulses of a pose (the torque and speed ratings do not).
    pub const fn is_mapping(self) -> bool {
        !matches!(self, ServoParam::TorqueKgcm | ServoParam::SpeedS60Deg)
    }

    fn get(self, s: &ServoConfig) -> SettingValue {
        match self {
            ServoParam::TrimUs => SettingValue::Number(s.home_us),
            ServoParam::RateUsRad => SettingValue::Number(s.rate_us_per_rad),
            ServoParam::Dir => SettingValue::Dir(s.direction),
            ServoParam::MinUs => SettingValue::Number(s.min_us),
            ServoParam::MaxUs => SettingValue::Number(s.max_us),
            // Not mapping fields: see Settings::get.
            ServoParam::TorqueKgcm | ServoParam::SpeedS60Deg => SettingValue::Number(0.0),
        }
    }

    fn set(self, s: &mut ServoConfig, value: SettingValue) {
        match (self, value) {
            (ServoParam::TrimUs, SettingValue::Number(v)) => s.home_us = v,
            (ServoParam::RateUsRad, SettingValue::Number(v)) => s.rate_us_per_rad = v,
            (ServoParam::Dir, SettingValue::Dir(d)) => s.direction = d,
            (ServoParam::MinUs, SettingValue::Number(v)) => s.min_us = v,
            (ServoParam::MaxUs, SettingValue::Number(v)) => s.max_us = v,
            _ => {} // a value of the wrong kind is never produced by `parse_value`
        }
    }
}

/// A setting's name.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SettingId {
    /// `frame_hz`.
    FrameHz,
    /// `baud`.
    Baud,
    /// `echo`.
    Echo,
    /// `speed_mm_s`.
    SpeedMmS,
    /// `speed_deg_s`.
    SpeedDegS,
    /// `accel_mm_s2`.
    AccelMmS2,
    /// `accel_deg_s2`.
    AccelDegS2,
    /// `link_timeout_s`.
    LinkTimeoutS,
    /// A build number.
    Layout(LayoutParam),
    /// A servo field.
    Servo(ServoSel, ServoParam),
    /// `stream.x_mm` .. `stream.yaw_deg`: an axis' full scale.
    StreamScale(Axis),
    /// `stream.bits`.
    StreamBits,
    /// `stream.axisN`: the axis of a text frame's count N (1..=6).
    StreamAxis(u8),
    /// `stream.max_step_pct`: the step guard.
    StreamMaxStep,
    /// `estop_pin`.
    EstopPin,
    /// `estop_action`.
    EstopAction,
    /// `power_pin`.
    PowerPin,
    /// `payload_g`.
    PayloadG,
    /// `payload_com_x_mm`, `payload_com_y_mm`, `payload_com_z_mm`: the centre of mass along
    /// x (0), y (1) or z (2).
    PayloadCom(u8),
    /// `pivot_x_mm`, `pivot_y_mm`, `pivot_z_mm`: the pivot (the rotations' centre) along x (0),
    /// y (1) or z (2).
    Pivot(u8),
}

/// The words `stream.axisN` takes, [`SettingValue::Choice`] indices: the axes in pose order,
/// then `none`.
pub const STREAM_AXIS_WORDS: &[&str] = &["x", "y", "z", "roll", "pitch", "yaw", "none"];
/// The words `estop_action` takes, in [`EstopAction`] order.
pub const ESTOP_ACTION_WORDS: &[&str] = &["freeze", "home"];

/// The form and range of a setting's value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
    /// A whole number in `min..=max`, or, if `list` is not empty, one of `list`.
    Whole {
        /// Smallest.
        min: u32,
        /// Largest.
        max: u32,
        /// The only values allowed, if not empty.
        list: &'static [u32],
        /// Unit.
        unit: &'static str,
    },
    /// A decimal in `min..=max` (or 0 / `off` when `off_allowed`).
    Number {
        /// Smallest (besides 0).
        min: f32,
        /// Largest.
        max: f32,
        /// Unit.
        unit: &'static str,
        /// 0 and `off` mean "off".
        off_allowed: bool,
        /// Decimals shown by `config`.
        decimals: u8,
    },
    /// `on` / `off` (or `1` / `0`: [`FLAG_WORDS`]).
    Flag,
    /// `normal` / `reversed` (or `1` / `-1`: [`DIR_WORDS`]).
    Dir,
    /// One of these words.
    Choice(&'static [&'static str]),
    /// A GPIO number from [`FREE_GPIOS`], or `off`.
    Pin,
}

/// Every word a flag ([`Kind::Flag`]) takes and what it means: `on` / `off`, and the `1` / `0`
/// a script writes. `config` shows the first two; docs/settings.md names them all (tested).
pub const FLAG_WORDS: [(&str, bool); 4] = [("on", true), ("off", false), ("1", true), ("0", false)];

/// Every word a direction ([`Kind::Dir`]) takes and what it means: `normal` / `reversed`, and
/// the sign a script writes (`1`, `+1`, `-1`; `0` is no direction). `config` shows the first
/// two; docs/settings.md names them all (tested).
pub const DIR_WORDS: [(&str, Direction); 5] = [
    ("normal", Direction::Normal),
    ("reversed", Direction::Reversed),
    ("1", Direction::Normal),
    ("+1", Direction::Normal),
    ("-1", Direction::Reversed),
];

/// A parsed setting value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SettingValue {
    /// For [`Kind::Whole`].
    Whole(u32),
    /// For [`Kind::Number`].
    Number(f32),
    /// For [`Kind::Flag`].
    Flag(bool),
    /// For [`Kind::Dir`].
    Dir(Direction),
    /// For [`Kind::Choice`]: the index of the word.
    Choice(u8),
    /// For [`Kind::Pin`]: the GPIO, or `None` for off.
    Pin(Option<u8>),
}

/// What a refused setting value was expected to be (for [`SettingError::BadValue`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Expected {
    /// A whole number (`frame_hz`, `baud`).
    WholeNumber,
    /// `on` or `off`.
    OnOrOff,
    /// `normal` or `reversed`.
    NormalOrReversed,
    /// One of these words.
    OneOf(&'static [&'static str]),
    /// A free GPIO ([`FREE_GPIOS`]) or `off`.
    FreePin,
    /// A number with at most two decimals (a whole number of hundredths: what the flash record
    /// keeps of a servo's rated speed).
    Hundredths,
}

/// Why a setting value, or a set of settings, is refused.
#[derive(Debug, Clone, PartialEq)]
pub enum SettingError {
    /// The value is not a decimal number.
    BadNumber {
        /// The setting.
        setting: SettingId,
        /// What was typed.
        word: Word,
    },
    /// The value is NaN or infinity.
    NotFinite {
        /// The setting.
        setting: SettingId,
        /// What was typed.
        word: Word,
    },
    /// The value does not fit (e.g. `1e39`).
    NumberTooLarge {
        /// The setting.
        setting: SettingId,
        /// What was typed.
        word: Word,
    },
    /// The value has the wrong form (e.g. `echo maybe`).
    BadValue {
        /// The setting.
        setting: SettingId,
        /// What was typed.
        word: Word,
        /// What is accepted.
        expected: Expected,
    },
    /// A number that is not one of the values the setting allows (`baud`).
    NotOneOf {
        /// The setting.
        setting: SettingId,
        /// The value given, as typed.
        word: Word,
        /// The values allowed.
        allowed: &'static [u32],
    },
    /// The value is outside the setting's range.
    OutOfRange {
        /// The setting.
        setting: SettingId,
        /// The value given.
        value: f32,
        /// Smallest value accepted.
        min: f32,
        /// Largest value accepted.
        max: f32,
        /// Unit of the three numbers (may be empty).
        unit: &'static str,
        /// Whether 0 / `off` is also accepted.
        off_allowed: bool,
    },
    /// The resulting servo settings are inconsistent.
    BadServoConfig(ServoError),
    /// The resulting geometry is not a buildable platform.
    BadGeometry(GeometryError),
    /// Two `stream.axisN` name the same axis.
    StreamAxisTwice {
        /// The axis.
        axis: Axis,
        /// The first count that has it (1..=6).
        first: u8,
        /// The other (1..=6).
        second: u8,
    },
    /// `estop_pin` and `power_pin` are the same GPIO.
    PinTwice {
        /// The GPIO.
        pin: u8,
    },
}

const fn number(min: f32, max: f32, unit: &'static str, decimals: u8) -> Kind {
    Kind::Number {
        min,
        max,
        unit,
        off_allowed: false,
        decimals,
    }
}

const fn number_or_off(min: f32, max: f32, unit: &'static str) -> Kind {
    Kind::Number {
        min,
        max,
        unit,
        off_allowed: true,
        decimals: 3,
    }
}

impl SettingId {
    /// The settings that are not per servo, in listing order.
    pub const GLOBAL: [SettingId; 38] = [
        SettingId::FrameHz,
        SettingId::Baud,
        SettingId::Echo,
        SettingId::SpeedMmS,
        SettingId::SpeedDegS,
        SettingId::AccelMmS2,
        SettingId::AccelDegS2,
        SettingId::LinkTimeoutS,
        SettingId::Layout(LayoutParam::BaseRadiusMm),
        SettingId::Layout(LayoutParam::BaseHalfAngleDeg),
        SettingId::Layout(LayoutParam::PlatformRadiusMm),
        SettingId::Layout(LayoutParam::PlatformHalfAngleDeg),
        SettingId::Layout(LayoutParam::ArmMm),
        SettingId::Layout(LayoutParam::RodMm),
        SettingId::StreamScale(Axis::X),
        SettingId::StreamScale(Axis::Y),
        SettingId::StreamScale(Axis::Z),
        SettingId::StreamScale(Axis::Roll),
        SettingId::StreamScale(Axis::Pitch),
        SettingId::StreamScale(Axis::Yaw),
        SettingId::StreamBits,
        SettingId::StreamAxis(1),
        SettingId::StreamAxis(2),
        SettingId::StreamAxis(3),
        SettingId::StreamAxis(4),
        SettingId::StreamAxis(5),
        SettingId::StreamAxis(6),
        SettingId::StreamMaxStep,
        SettingId::EstopPin,
        SettingId::EstopAction,
        SettingId::PowerPin,
        SettingId::PayloadG,
        SettingId::PayloadCom(0),
        SettingId::PayloadCom(1),
        SettingId::PayloadCom(2),
        SettingId::Pivot(0),
        SettingId::Pivot(1),
        SettingId::Pivot(2),
    ];

    /// Looks a name up (already lowercase).
    pub fn parse(name: &str) -> Option<SettingId> {
        if let Some(id) = SettingId::GLOBAL
            .into_iter()
            .find(|id| id.simple_name() == Some(name))
        {
            return Some(id);
        }
        let (servo, field) = name.split_once('.')?;
        let sel = match servo {
            "servos" => ServoSel::All,
            _ => {
                let n = servo.strip_prefix("servo")?;
                match n.as_bytes() {
                    [d @ b'1'..=b'6'] => ServoSel::One(d - b'0'),
                    _ => return None,
                }
            }
        };
        let param = ServoParam::ALL.into_iter().find(|p| p.name() == field)?;
        Some(SettingId::Servo(sel, param))
    }

    fn simple_name(self) -> Option<&'static str> {
        Some(match self {
            SettingId::FrameHz => "frame_hz",
            SettingId::Baud => "baud",
            SettingId::Echo => "echo",
            SettingId::SpeedMmS => "speed_mm_s",
            SettingId::SpeedDegS => "speed_deg_s",
            SettingId::AccelMmS2 => "accel_mm_s2",
            SettingId::AccelDegS2 => "accel_deg_s2",
            SettingId::LinkTimeoutS => "link_timeout_s",
            SettingId::Layout(p) => p.name(),
            SettingId::Servo(..) => return None,
            SettingId::StreamScale(axis) => match axis {
                Axis::X => "stream.x_mm",
                Axis::Y => "stream.y_mm",
                Axis::Z => "stream.z_mm",
                Axis::Roll => "stream.roll_deg",
                Axis::Pitch => "stream.pitch_deg",
                Axis::Yaw => "stream.yaw_deg",
            },
            SettingId::StreamBits => "stream.bits",
            SettingId::StreamAxis(n) => match n {
                1 => "stream.axis1",
                2 => "stream.axis2",
                3 => "stream.axis3",
                4 => "stream.axis4",
                5 => "stream.axis5",
                _ => "stream.axis6",
            },
            SettingId::StreamMaxStep => "stream.max_step_pct",
            SettingId::EstopPin => "estop_pin",
            SettingId::EstopAction => "estop_action",
            SettingId::PowerPin => "power_pin",
            SettingId::PayloadG => "payload_g",
            SettingId::PayloadCom(k) => match k {
                0 => "payload_com_x_mm",
                1 => "payload_com_y_mm",
                _ => "payload_com_z_mm",
            },
            SettingId::Pivot(k) => match k {
                0 => "pivot_x_mm",
                1 => "pivot_y_mm",
                _ => "pivot_z_mm",
            },
        })
    }

    /// The form and range of this setting's value.
    pub const fn kind(self) -> Kind {
        match self {
            SettingId::FrameHz => Kind::Whole {
                min: FRAME_HZ_MIN as u32,
                max: FRAME_HZ_MAX as u32,
                list: &[],
                unit: "Hz",
            },
            SettingId::Baud => Kind::Whole {
                min: 0,
                max: u32::MAX,
                list: &BAUD_RATES,
                unit: "baud",
            },
            SettingId::Echo => Kind::Flag,
            SettingId::SpeedMmS => number_or_off(0.1, 1000.0, "mm/s"),
            SettingId::SpeedDegS => number_or_off(0.1, 3600.0, "deg/s"),
            SettingId::AccelMmS2 => number_or_off(1.0, 100_000.0, "mm/s^2"),
            SettingId::AccelDegS2 => number_or_off(1.0, 1_000_000.0, "deg/s^2"),
            SettingId::LinkTimeoutS => number_or_off(0.1, 3600.0, "s"),
            SettingId::StreamScale(axis) => {
                if axis.is_angle() {
                    number(-90.0, 90.0, "deg", 3)
                } else {
                    number(-500.0, 500.0, "mm", 3)
                }
            }
            SettingId::StreamBits => Kind::Whole {
                min: TEXT_BITS_MIN as u32,
                max: TEXT_BITS_MAX as u32,
                list: &[],
                unit: "bits",
            },
            SettingId::StreamAxis(_) => Kind::Choice(STREAM_AXIS_WORDS),
            SettingId::StreamMaxStep => Kind::Number {
                min: 0.1,
                max: 100.0,
                unit: "%",
                off_allowed: true,
                decimals: 1,
            },
            SettingId::EstopAction => Kind::Choice(ESTOP_ACTION_WORDS),
            SettingId::EstopPin | SettingId::PowerPin => Kind::Pin,
            SettingId::PayloadG => number(0.0, MAX_PAYLOAD_G, "g", 1),
            SettingId::PayloadCom(_) => number(-MAX_COM_MM, MAX_COM_MM, "mm", 3),
            SettingId::Pivot(_) => number(-MAX_PIVOT_MM, MAX_PIVOT_MM, "mm", 3),
            SettingId::Layout(p) => match p {
                LayoutParam::BaseRadiusMm | LayoutParam::PlatformRadiusMm => {
                    number(1.0, 1000.0, "mm", 3)
                }
                LayoutParam::BaseHalfAngleDeg | LayoutParam::PlatformHalfAngleDeg => {
                    number(0.0, 60.0, "deg", 3)
                }
                LayoutParam::ArmMm => number(1.0, 500.0, "mm", 3),
                LayoutParam::RodMm => number(1.0, 2000.0, "mm", 3),
            },
            SettingId::Servo(_, p) => match p {
                ServoParam::TrimUs | ServoParam::MinUs | ServoParam::MaxUs => {
                    number(MIN_PULSE_US, MAX_PULSE_US, "us", 2)
                }
                ServoParam::RateUsRad => {
                    number(MIN_RATE_US_PER_RAD, MAX_RATE_US_PER_RAD, "us/rad", 3)
                }
                ServoParam::Dir => Kind::Dir,
                ServoParam::TorqueKgcm => Kind::Number {
                    min: MIN_TORQUE_KGCM,
                    max: MAX_TORQUE_KGCM,
                    unit: "kgf cm",
                    off_allowed: true,
                    decimals: 2,
                },
                ServoParam::SpeedS60Deg => Kind::Number {
                    min: MIN_S_PER_60DEG,
                    max: MAX_S_PER_60DEG,
                    unit: "s/60deg",
                    off_allowed: true,
                    decimals: 2,
                },
            },
        }
    }

    /// What this setting is, in a few words: the one wording of its meaning, which the host
    /// tool writes beside each key of a build file and `docs/settings.md` shows (its table's
    /// meaning column is checked against this by `control/tests/documents.rs`).
    pub const fn meaning(self) -> &'static str {
        match self {
            SettingId::FrameHz => "servo frame rate",
            SettingId::Baud => "UART0 baud rate",
            SettingId::Echo => "echo and prompt on the link",
            SettingId::SpeedMmS => "linear speed limit",
            SettingId::SpeedDegS => "angular speed limit",
            SettingId::AccelMmS2 => "linear acceleration limit",
            SettingId::AccelDegS2 => "angular acceleration limit",
            SettingId::LinkTimeoutS => "return home after this long without a command",
            SettingId::Layout(p) => match p {
                LayoutParam::BaseRadiusMm => "servo shaft circle radius",
                LayoutParam::BaseHalfAngleDeg => "half the angle between a servo pair",
                LayoutParam::PlatformRadiusMm => "platform joint circle radius",
                LayoutParam::PlatformHalfAngleDeg => "half the angle between a joint pair",
                LayoutParam::ArmMm => "servo arm (horn) length a",
                LayoutParam::RodMm => "rod length s",
            },
            SettingId::Servo(_, p) => match p {
                ServoParam::TrimUs => "home pulse W0",
                ServoParam::RateUsRad => "servo rate r",
                ServoParam::Dir => "direction",
                ServoParam::MinUs => "lowest pulse",
                ServoParam::MaxUs => "highest pulse",
                ServoParam::TorqueKgcm => "rated torque",
                ServoParam::SpeedS60Deg => "rated speed: time to turn 60 degrees unloaded",
            },
            SettingId::StreamScale(_) => "stream full scale of the axis",
            SettingId::StreamBits => "bits of a text frame's counts",
            SettingId::StreamAxis(_) => "the axis this text-frame count drives",
            SettingId::StreamMaxStep => "largest step between two frames, % of full scale",
            SettingId::EstopPin => "emergency-stop input",
            SettingId::EstopAction => "what an open e-stop does",
            SettingId::PowerPin => "servo-power enable output",
            SettingId::PayloadG => "mass the platform carries (0: none)",
            SettingId::PayloadCom(k) => match k {
                0 => "payload centre of mass, platform frame x",
                1 => "payload centre of mass, platform frame y",
                _ => "payload centre of mass, platform frame z (up)",
            },
            SettingId::Pivot(k) => match k {
                0 => "rotation centre (pivot), platform frame x",
                1 => "rotation centre (pivot), platform frame y",
                _ => "rotation centre (pivot), platform frame z (up)",
            },
        }
    }

    /// True for the link settings (`baud`, `echo`), which are not part of [`Settings`].
    pub const fn is_link(self) -> bool {
        matches!(self, SettingId::Baud | SettingId::Echo)
    }

    /// Parses and range-checks a value typed for this setting (already lowercase).
    pub fn parse_value(self, text: &str) -> Result<SettingValue, SettingError> {
        let setting = self;
        let number_error = |e: NumberError| match e {
            NumberError::Syntax => SettingError::BadNumber {
                setting,
                word: word(text),
            },
            NumberError::NotFinite => SettingError::NotFinite {
                setting,
                word: word(text),
            },
            NumberError::TooLarge => SettingError::NumberTooLarge {
                setting,
                word: word(text),
            },
            NumberError::NotWhole => SettingError::BadValue {
                setting,
                word: word(text),
                expected: Expected::WholeNumber,
            },
        };
        let bad_value = |expected| SettingError::BadValue {
            setting,
            word: word(text),
            expected,
        };
        let value = match self.kind() {
            Kind::Whole {
                min,
                max,
                list,
                unit,
            } => match parse_u32(text) {
                Ok(v) => SettingValue::Whole(v),
                // A number, but not a whole one: a negative or fractional number outside the
                // range is out of range (named as such); in range, it is not whole.
                Err(NumberError::NotWhole) => {
                    let v = parse_f32(text).unwrap_or(0.0);
                    return Err(if !list.is_empty() {
                        SettingError::NotOneOf {
                            setting,
                            word: word(text),
                            allowed: list,
                        }
                    } else if !(min as f32..=max as f32).contains(&v) {
                        SettingError::OutOfRange {
                            setting,
                            value: v,
                            min: min as f32,
                            max: max as f32,
                            unit,
                            off_allowed: false,
                        }
                    } else {
                        number_error(NumberError::NotWhole)
                    });
                }
                Err(e) => return Err(number_error(e)),
            },
            Kind::Number { off_allowed, .. } => {
                if off_allowed && text == "off" {
                    SettingValue::Number(0.0)
                } else {
                    SettingValue::Number(parse_f32(text).map_err(number_error)?)
                }
            }
            Kind::Flag => match FLAG_WORDS.iter().find(|(w, _)| *w == text) {
                Some(&(_, on)) => SettingValue::Flag(on),
                None => return Err(bad_value(Expected::OnOrOff)),
            },
            Kind::Dir => match DIR_WORDS.iter().find(|(w, _)| *w == text) {
                Some(&(_, direction)) => SettingValue::Dir(direction),
                None => return Err(bad_value(Expected::NormalOrReversed)),
            },
            Kind::Choice(words) => match words.iter().position(|w| *w == text) {
                // At most a handful of words: the index fits.
                Some(i) => SettingValue::Choice(i as u8),
                None => return Err(bad_value(Expected::OneOf(words))),
            },
            Kind::Pin => match (text, parse_u32(text)) {
                ("off", _) => SettingValue::Pin(None),
                (_, Ok(gpio)) if FREE_GPIOS.contains(&gpio) => {
                    // FREE_GPIOS are below 30.
                    SettingValue::Pin(Some(gpio as u8))
                }
                _ => return Err(bad_value(Expected::FreePin)),
            },
        };
        self.check(value)?;
        if let (SettingId::Servo(_, ServoParam::SpeedS60Deg), SettingValue::Number(v)) =
            (self, value)
        {
            // Kept as hundredths in flash: a value with more decimals would not come back as
            // given after a save.
            if ServoSpeeds::quantise(v) != v {
                return Err(bad_value(Expected::Hundredths));
            }
        }
        Ok(value)
    }

    /// Checks that a value has this setting's form and range.
    pub fn check(self, value: SettingValue) -> Result<(), SettingError> {
        let setting = self;
        match (self.kind(), value) {
            (
                Kind::Whole {
                    min,
                    max,
                    list,
                    unit,
                },
                SettingValue::Whole(v),
            ) => {
                if !list.is_empty() {
                    return if list.contains(&v) {
                        Ok(())
                    } else {
                        let mut text = heapless::String::<10>::new();
                        // u32::MAX has 10 digits: this always fits.
                        let _ = fmt::write(&mut text, format_args!("{v}"));
                        Err(SettingError::NotOneOf {
                            setting,
                            word: word(&text),
                            allowed: list,
                        })
                    };
                }
                if (min..=max).contains(&v) {
                    Ok(())
                } else {
                    Err(SettingError::OutOfRange {
                        setting,
                        value: v as f32,
                        min: min as f32,
                        max: max as f32,
                        unit,
                        off_allowed: false,
                    })
                }
            }
            (
                Kind::Number {
                    min,
                    max,
                    unit,
                    off_allowed,
                    ..
                },
                SettingValue::Number(v),
            ) => {
                if (off_allowed && v == 0.0) || (min..=max).contains(&v) {
                    Ok(())
                } else {
                    Err(SettingError::OutOfRange {
                        setting,
                        value: v,
                        min,
                        max,
                        unit,
                        off_allowed,
                    })
                }
            }
            (Kind::Flag, SettingValue::Flag(_)) | (Kind::Dir, SettingValue::Dir(_)) => Ok(()),
            (Kind::Choice(words), SettingValue::Choice(i)) if usize::from(i) < words.len() => {
                Ok(())
            }
            (Kind::Pin, SettingValue::Pin(pin))
                if pin.is_none_or(|p| FREE_GPIOS.contains(&u32::from(p))) =>
            {
                Ok(())
            }
            // A value of another kind: only a caller's mistake (`parse_value` never makes one).
            (kind, _) => Err(SettingError::BadValue {
                setting,
                word: word("?"),
                expected: match kind {
                    Kind::Flag => Expected::OnOrOff,
                    Kind::Dir => Expected::NormalOrReversed,
                    Kind::Choice(words) => Expected::OneOf(words),
                    Kind::Pin => Expected::FreePin,
                    Kind::Whole { .. } | Kind::Number { .. } => Expected::WholeNumber,
                },
            }),
        }
    }
}

impl Display for SettingId {
    fn fmt(&self, f: &mut Formatter<'_>) -> fmt::Result {
        match self {
            SettingId::Servo(ServoSel::One(n), p) => write!(f, "servo{n}.{}", p.name()),
            SettingId::Servo(ServoSel::All, p) => write!(f, "servos.{}", p.name()),
            other => f.write_str(other.simple_name().unwrap_or("?")),
        }
    }
}

impl Settings {
    /// The current value of a platform setting (`servos.x` reads servo 1); `None` for the link
    /// settings (see [`LinkSettings::get`]).
    pub fn get(&self, id: SettingId) -> Option<SettingValue> {
        Some(match id {
            SettingId::FrameHz => SettingValue::Whole(u32::from(self.frame_hz)),
            SettingId::Baud | SettingId::Echo => return None,
            SettingId::SpeedMmS => SettingValue::Number(self.speed_mm_s),
            SettingId::SpeedDegS => SettingValue::Number(self.speed_deg_s),
            SettingId::AccelMmS2 => SettingValue::Number(self.accel_mm_s2),
            SettingId::AccelDegS2 => SettingValue::Number(self.accel_deg_s2),
            SettingId::LinkTimeoutS => SettingValue::Number(self.link_timeout_s),
            SettingId::Layout(p) => SettingValue::Number(p.get(&self.layout)),
            SettingId::StreamScale(axis) => {
                SettingValue::Number(self.stream.full_scale[axis as usize])
            }
            SettingId::StreamBits => SettingValue::Whole(u32::from(self.stream.text_bits)),
            SettingId::StreamAxis(n) => {
                let slot = usize::from(n).clamp(1, 6) - 1;
                let axis = self.stream.text_order[slot];
                // `none` is the word after the six axes.
                SettingValue::Choice(axis.map_or(6, |a| a as u8))
            }
            SettingId::StreamMaxStep => SettingValue::Number(self.stream.max_step_pct),
            SettingId::EstopPin => SettingValue::Pin(self.safety.estop_pin),
            SettingId::EstopAction => SettingValue::Choice(self.safety.estop_action as u8),
            SettingId::PowerPin => SettingValue::Pin(self.safety.power_pin),
            SettingId::PayloadG => SettingValue::Number(self.payload.mass_g),
            SettingId::PayloadCom(k) => {
                SettingValue::Number(self.payload.com_mm[usize::from(k).min(2)])
            }
            SettingId::Pivot(k) => SettingValue::Number(self.pivot_mm[usize::from(k).min(2)]),
            SettingId::Servo(sel, p) => {
                let index = match sel {
                    ServoSel::One(n) => usize::from(n).saturating_sub(1).min(LEGS - 1),
                    ServoSel::All => 0,
                };
                match p {
                    ServoParam::TorqueKgcm => SettingValue::Number(self.payload.torque_kgcm[index]),
                    ServoParam::SpeedS60Deg => {
                        SettingValue::Number(self.servo_speed.s_per_60deg[index])
                    }
                    _ => p.get(&self.servos.0[index]),
                }
            }
        })
    }

    /// A copy with one platform value replaced (not validated: see [`Settings::validate`]). A
    /// link setting, or a value of the wrong kind for the setting, leaves it unchanged.
    pub fn with(&self, id: SettingId, value: SettingValue) -> Settings {
        let mut s = *self;
        match (id, value) {
            (SettingId::FrameHz, SettingValue::Whole(v)) => {
                s.frame_hz = u16::try_from(v).unwrap_or(u16::MAX)
            }
            (SettingId::SpeedMmS, SettingValue::Number(v)) => s.speed_mm_s = v,
            (SettingId::SpeedDegS, SettingValue::Number(v)) => s.speed_deg_s = v,
            (SettingId::AccelMmS2, SettingValue::Number(v)) => s.accel_mm_s2 = v,
            (SettingId::AccelDegS2, SettingValue::Number(v)) => s.accel_deg_s2 = v,
            (SettingId::LinkTimeoutS, SettingValue::Number(v)) => s.link_timeout_s = v,
            (SettingId::Layout(p), SettingValue::Number(v)) => *p.slot(&mut s.layout) = v,
            (SettingId::StreamScale(axis), SettingValue::Number(v)) => {
                s.stream.full_scale[axis as usize] = v
            }
            (SettingId::StreamBits, SettingValue::Whole(v)) => {
                s.stream.text_bits = u8::try_from(v).unwrap_or(u8::MAX)
            }
            (SettingId::StreamAxis(n @ 1..=6), SettingValue::Choice(i)) => {
                s.stream.text_order[usize::from(n) - 1] = Axis::ALL.get(usize::from(i)).copied()
            }
            (SettingId::StreamMaxStep, SettingValue::Number(v)) => {
                // Kept to tenths, as the flash record holds it (out-of-range values stay out
                // of range for validation to refuse).
                s.stream.max_step_pct = if (0.0..=100.0).contains(&v) {
                    StreamSettings::quantise_step_pct(v)
                } else {
                    v
                }
            }
            (SettingId::EstopPin, SettingValue::Pin(pin)) => s.safety.estop_pin = pin,
            (SettingId::EstopAction, SettingValue::Choice(i)) => {
                s.safety.estop_action = if i == 1 {
                    EstopAction::Home
                } else {
                    EstopAction::Freeze
                }
            }
            (SettingId::PowerPin, SettingValue::Pin(pin)) => s.safety.power_pin = pin,
            (SettingId::PayloadG, SettingValue::Number(v)) => s.payload.mass_g = v,
            (SettingId::PayloadCom(k @ 0..=2), SettingValue::Number(v)) => {
                s.payload.com_mm[usize::from(k)] = v
            }
            (SettingId::Pivot(k @ 0..=2), SettingValue::Number(v)) => {
                s.pivot_mm[usize::from(k)] = v
            }
            (SettingId::Servo(sel, ServoParam::TorqueKgcm), SettingValue::Number(v)) => {
                // Kept to hundredths, as the flash record holds it (out-of-range values stay
                // out of range for validation to refuse).
                let v = if (0.0..=MAX_TORQUE_KGCM).contains(&v) {
                    PayloadSettings::quantise_kgcm(v)
                } else {
                    v
                };
                for (i, rating) in s.payload.torque_kgcm.iter_mut().enumerate() {
                    if sel == ServoSel::All || sel == ServoSel::One(i as u8 + 1) {
                        *rating = v;
                    }
                }
            }
            (SettingId::Servo(sel, ServoParam::SpeedS60Deg), SettingValue::Number(v)) => {
                // Kept to hundredths, as the flash record holds it (out-of-range values stay
                // out of range for validation to refuse).
                let v = if (0.0..=MAX_S_PER_60DEG).contains(&v) {
                    ServoSpeeds::quantise(v)
                } else {
                    v
                };
                for (i, rating) in s.servo_speed.s_per_60deg.iter_mut().enumerate() {
                    if sel == ServoSel::All || sel == ServoSel::One(i as u8 + 1) {
                        *rating = v;
                    }
                }
            }
            (SettingId::Servo(sel, p), value) => {
                for (i, servo) in s.servos.0.iter_mut().enumerate() {
                    if sel == ServoSel::All || sel == ServoSel::One(i as u8 + 1) {
                        p.set(servo, value);
                    }
                }
            }
            _ => {}
        }
        s
    }

    /// Checks every value's range, the servo set and the geometry; returns the IK of the
    /// geometry (which holds the geometry) turning about the pivot, built with `libm`.
    pub fn validate(&self) -> Result<Solver, SettingError> {
        self.validate_with::<Libm>()
    }

    /// [`Settings::validate`], the geometry built with `M`'s sine and cosine.
    pub fn validate_with<M: Math>(&self) -> Result<Solver, SettingError> {
        self.check_values()?;
        let geometry = self
            .layout
            .build_with::<M>()
            .map_err(SettingError::BadGeometry)?;
        let solver = Solver::new_with::<M>(geometry).map_err(SettingError::BadGeometry)?;
        Ok(self.about_pivot(solver))
    }

    /// `solver` turning about this pivot ([`Settings::pivot_mm`]). Every pivot within range
    /// ([`MAX_PIVOT_MM`] per axis, checked by [`Settings::check_values`]) is one the IK takes;
    /// one out of range leaves the solver's rotation centre as it was.
    pub fn about_pivot(&self, mut solver: Solver) -> Solver {
        // (A refused centre changes nothing: `set_rotation_centre_mm` checks it first.)
        let _ = solver.set_rotation_centre_mm(Vec3::from(self.pivot_mm));
        solver
    }

    /// Checks every value's range and the servo set, not the geometry.
    pub fn check_values(&self) -> Result<(), SettingError> {
        for id in SettingId::GLOBAL {
            if let Some(value) = self.get(id) {
                id.check(value)?;
            }
        }
        for servo in 1..=LEGS as u8 {
            for p in ServoParam::ALL {
                let id = SettingId::Servo(ServoSel::One(servo), p);
                if let Some(value) = self.get(id) {
                    id.check(value)?;
                }
            }
        }
        self.servos
            .validate()
            .map_err(SettingError::BadServoConfig)?;
        let order = &self.stream.text_order;
        for (i, a) in order.iter().enumerate() {
            for (j, b) in order.iter().enumerate().skip(i + 1) {
                if let (Some(axis), true) = (a, a == b) {
                    return Err(SettingError::StreamAxisTwice {
                        axis: *axis,
                        first: i as u8 + 1,
                        second: j as u8 + 1,
                    });
                }
            }
        }
        match (self.safety.estop_pin, self.safety.power_pin) {
            (Some(a), Some(b)) if a == b => Err(SettingError::PinTwice { pin: a }),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(name: &str, value: &str) -> Result<Settings, SettingError> {
        let id = SettingId::parse(name).expect("known name");
        let s = Settings::default().with(id, id.parse_value(value)?);
        s.validate()?;
        Ok(s)
    }

    #[test]
    fn defaults_are_valid_and_as_documented() {
        let s = Settings::default();
        s.validate().unwrap();
        assert_eq!(s.frame_hz, 50);
        assert_eq!(s.link_timeout_s, 0.0);
        assert_eq!(s.servos, ServoSet::default());
        let link = LinkSettings::default();
        assert_eq!((link.baud, link.echo), (115_200, true));
    }

    #[test]
    fn every_name_parses_back_from_its_display() {
        let mut ids: std::vec::Vec<SettingId> = SettingId::GLOBAL.to_vec();
        for p in ServoParam::ALL {
            ids.push(SettingId::Servo(ServoSel::All, p));
            for n in 1..=6 {
                ids.push(SettingId::Servo(ServoSel::One(n), p));
            }
        }
        for id in ids {
            let name = std::format!("{id}");
            assert_eq!(SettingId::parse(&name), Some(id), "{name}");
        }
        for bad in [
            "servo0.trim_us",
            "servo7.trim_us",
            "servo1.trim",
            "servo12.dir",
            "servo.dir",
            "speed",
            "",
        ] {
            assert_eq!(SettingId::parse(bad), None, "{bad}");
        }
    }

    #[test]
    fn values_are_set() {
        assert_eq!(parse("frame_hz", "333").unwrap().frame_hz, 333);
        assert_eq!(parse("speed_mm_s", "off").unwrap().speed_mm_s, 0.0);
        assert_eq!(parse("speed_deg_s", "0").unwrap().speed_deg_s, 0.0);
        assert_eq!(parse("link_timeout_s", "2.5").unwrap().link_timeout_s, 2.5);
        assert_eq!(parse("rod_mm", "121").unwrap().layout.rod_mm, 121.0);
        let s = parse("servo3.trim_us", "1520").unwrap();
        assert_eq!(s.servos.0[2].home_us, 1520.0);
        assert_eq!(s.servos.0[1].home_us, 1500.0);
        let s = parse("servo2.dir", "reversed").unwrap();
        assert_eq!(s.servos.0[1].direction, Direction::Reversed);
        let s = parse("servos.rate_us_rad", "600").unwrap();
        assert!(s.servos.0.iter().all(|c| c.rate_us_per_rad == 600.0));
        assert_eq!(parse("payload_g", "1250.5").unwrap().payload.mass_g, 1250.5);
        let s = parse("payload_com_z_mm", "-30").unwrap();
        assert_eq!(s.payload.com_mm, [0.0, 0.0, -30.0]);
        let s = parse("servo4.torque_kgcm", "2.505").unwrap();
        assert_eq!(s.payload.torque_kgcm, [0.0, 0.0, 0.0, 2.51, 0.0, 0.0]);
        assert_eq!(
            s.servos,
            ServoSet::default(),
            "a rating is not a pulse mapping"
        );
        let s = parse("servos.torque_kgcm", "12").unwrap();
        assert_eq!(s.payload.torque_kgcm, [12.0; 6]);
        assert_eq!(
            s.get(SettingId::parse("servo6.torque_kgcm").unwrap()),
            Some(SettingValue::Number(12.0))
        );
        let s = parse("servos.torque_kgcm", "off").unwrap();
        assert_eq!(s.payload.torque_kgcm, [0.0; 6]);
    }

    #[test]
    fn the_pivot_is_three_numbers_and_the_ik_turns_about_it() {
        let s = parse("pivot_z_mm", "120.5").unwrap();
        assert_eq!(s.pivot_mm, [0.0, 0.0, 120.5]);
        let s = parse("pivot_x_mm", "-1000").unwrap();
        assert_eq!(s.pivot_mm, [-1000.0, 0.0, 0.0]);
        assert_eq!(
            s.get(SettingId::parse("pivot_x_mm").unwrap()),
            Some(SettingValue::Number(-1000.0))
        );
        assert!(matches!(
            parse("pivot_y_mm", "1000.5"),
            Err(SettingError::OutOfRange {
                min: -1000.0,
                max: 1000.0,
                ..
            })
        ));
        assert!(matches!(
            parse("pivot_y_mm", "off"),
            Err(SettingError::BadNumber { .. })
        ));
        // The IK of valid settings turns about the pivot: with the pivot 100 mm up, a pose
        // pitched by 5 degrees puts the platform's joints where the same pitch about the
        // platform's centre does after a shift of (I - R) c = (-100 sin 5, 0, 100 (1 - cos 5)).
        let about = parse("pivot_z_mm", "100").unwrap().validate().unwrap();
        assert_eq!(about.rotation_centre_mm(), Vec3::new(0.0, 0.0, 100.0));
        let plain = Settings::default().validate().unwrap();
        assert_eq!(plain.rotation_centre_mm(), Vec3::zeros());
        let pitch = 5f64.to_radians();
        let shift = [-100.0 * pitch.sin(), 0.0, 100.0 * (1.0 - pitch.cos())];
        let pose = kinematics_core::Pose::from_degrees(0.0, 0.0, 0.0, 0.0, 5.0, 0.0);
        let shifted = kinematics_core::Pose::from_degrees(
            shift[0] as f32,
            shift[1] as f32,
            shift[2] as f32,
            0.0,
            5.0,
            0.0,
        );
        let a = about.arm_angles::<Libm>(&pose).unwrap();
        let b = plain.arm_angles::<Libm>(&shifted).unwrap();
        for i in 0..LEGS {
            assert!(
                (a[i] - b[i]).abs() < 1e-5,
                "leg {}: {} vs {}",
                i + 1,
                a[i],
                b[i]
            );
        }
    }

    #[test]
    fn speed_ratings_are_set_per_servo_or_all_to_hundredths() {
        let s = parse("servo2.speed_s_60deg", "0.12").unwrap();
        assert_eq!(s.servo_speed.s_per_60deg, [0.0, 0.12, 0.0, 0.0, 0.0, 0.0]);
        assert_eq!(
            s.servos,
            ServoSet::default(),
            "a rating is not a pulse mapping"
        );
        assert!(!ServoParam::SpeedS60Deg.is_mapping());
        let s = parse("servos.speed_s_60deg", "0.1").unwrap();
        assert_eq!(s.servo_speed.s_per_60deg, [0.1; 6]);
        assert_eq!(
            s.get(SettingId::parse("servo5.speed_s_60deg").unwrap()),
            Some(SettingValue::Number(0.1))
        );
        for text in ["off", "0"] {
            let s = parse("servos.speed_s_60deg", text).unwrap();
            assert_eq!(s.servo_speed.s_per_60deg, [0.0; 6], "{text}");
        }
        for (text, value) in [
            ("2.55", 2.55),
            ("0.01", 0.01),
            ("1e-1", 0.1),
            ("0.200", 0.2),
        ] {
            let s = parse("servo6.speed_s_60deg", text).unwrap();
            assert_eq!(s.servo_speed.s_per_60deg[5], value, "{text}");
        }
        use SettingError as E;
        // More decimals than the flash keeps: refused, not rounded.
        for text in ["0.125", "0.101", "1.5e-2", "0.0150"] {
            assert!(
                matches!(
                    parse("servo1.speed_s_60deg", text),
                    Err(E::BadValue {
                        expected: Expected::Hundredths,
                        ..
                    })
                ),
                "{text}"
            );
        }
        for text in ["2.56", "-0.1", "0.001", "300"] {
            assert!(
                matches!(
                    parse("servos.speed_s_60deg", text),
                    Err(E::OutOfRange {
                        min: 0.01,
                        max: 2.55,
                        ..
                    })
                ),
                "{text}"
            );
        }
        assert!(matches!(
            parse("servos.speed_s_60deg", "fast"),
            Err(E::BadNumber { .. })
        ));
    }

    #[test]
    fn payload_values_outside_their_ranges_are_refused() {
        use SettingError as E;
        let err = |name, value| parse(name, value).unwrap_err();
        assert!(matches!(err("payload_g", "-1"), E::OutOfRange { .. }));
        assert!(matches!(err("payload_g", "100001"), E::OutOfRange { .. }));
        assert!(matches!(
            err("payload_com_x_mm", "1001"),
            E::OutOfRange { .. }
        ));
        assert!(matches!(
            err("servo1.torque_kgcm", "601"),
            E::OutOfRange { .. }
        ));
        assert!(matches!(
            err("servo1.torque_kgcm", "0.001"),
            E::OutOfRange { .. }
        ));
        assert!(matches!(
            err("servo1.torque_kgcm", "-2"),
            E::OutOfRange { .. }
        ));
        assert!(matches!(err("payload_g", "nan"), E::NotFinite { .. }));
    }

    #[test]
    fn flags_and_directions_take_their_words_and_the_numbers_scripts_write() {
        for (text, on) in [("on", true), ("1", true), ("off", false), ("0", false)] {
            assert_eq!(
                SettingId::Echo.parse_value(text),
                Ok(SettingValue::Flag(on)),
                "{text}"
            );
        }
        for (text, direction) in [
            ("normal", Direction::Normal),
            ("1", Direction::Normal),
            ("+1", Direction::Normal),
            ("reversed", Direction::Reversed),
            ("-1", Direction::Reversed),
        ] {
            let one = parse("servo1.dir", text).unwrap();
            assert_eq!(one.servos.0[0].direction, direction, "servo1.dir {text}");
            let all = parse("servos.dir", text).unwrap();
            assert!(
                all.servos.0.iter().all(|c| c.direction == direction),
                "servos.dir {text}"
            );
        }
        // 0 has no sign, and a flag is not a direction nor the other way round.
        for (name, text) in [
            ("servos.dir", "0"),
            ("servo2.dir", "0"),
            ("servo2.dir", "on"),
            ("servo2.dir", "2"),
            ("echo", "normal"),
            ("echo", "-1"),
            ("echo", "2"),
        ] {
            let id = SettingId::parse(name).unwrap();
            assert!(
                matches!(id.parse_value(text), Err(SettingError::BadValue { .. })),
                "{name} {text}"
            );
        }
    }

    #[test]
    fn link_settings_parse_but_are_not_the_platform() {
        assert_eq!(
            SettingId::Baud.parse_value("921600"),
            Ok(SettingValue::Whole(921_600))
        );
        assert_eq!(
            SettingId::Echo.parse_value("off"),
            Ok(SettingValue::Flag(false))
        );
        let s = Settings::default();
        assert_eq!(s.with(SettingId::Baud, SettingValue::Whole(9600)), s);
        assert_eq!(s.get(SettingId::Echo), None);
        assert!(SettingId::Baud.is_link() && SettingId::Echo.is_link());
        assert!(!SettingId::FrameHz.is_link());
    }

    #[test]
    fn bad_values_are_refused_with_their_own_kinds() {
        use SettingError as E;
        let err = |name, value| parse(name, value).unwrap_err();
        let value_err = |name: &str, value| {
            SettingId::parse(name)
                .unwrap()
                .parse_value(value)
                .unwrap_err()
        };
        assert!(matches!(err("frame_hz", "49"), E::OutOfRange { .. }));
        assert!(matches!(err("frame_hz", "334"), E::OutOfRange { .. }));
        assert!(matches!(
            err("frame_hz", "50.5"),
            E::BadValue {
                expected: Expected::WholeNumber,
                ..
            }
        ));
        assert!(matches!(err("frame_hz", "fast"), E::BadNumber { .. }));
        assert!(matches!(
            err("frame_hz", "99999999999"),
            E::NumberTooLarge { .. }
        ));
        assert_eq!(
            value_err("baud", "1000000"),
            E::NotOneOf {
                setting: SettingId::Baud,
                word: word("1000000"),
                allowed: &BAUD_RATES,
            }
        );
        // A negative or fractional number is a number: out of range where it is, not "not a
        // whole number".
        assert!(matches!(
            err("frame_hz", "-50"),
            E::OutOfRange { value, min: 50.0, max: 333.0, .. } if value == -50.0
        ));
        assert!(matches!(err("frame_hz", "20.5"), E::OutOfRange { .. }));
        assert!(matches!(
            err("frame_hz", "-0"),
            E::OutOfRange { value, .. } if value == 0.0
        ));
        assert_eq!(
            value_err("baud", "-9600"),
            E::NotOneOf {
                setting: SettingId::Baud,
                word: word("-9600"),
                allowed: &BAUD_RATES,
            }
        );
        assert!(matches!(
            value_err("echo", "maybe"),
            E::BadValue {
                expected: Expected::OnOrOff,
                ..
            }
        ));
        assert!(matches!(err("speed_mm_s", "-1"), E::OutOfRange { .. }));
        assert!(matches!(err("speed_mm_s", "nan"), E::NotFinite { .. }));
        assert!(matches!(
            err("speed_mm_s", "1e39"),
            E::NumberTooLarge { .. }
        ));
        assert!(matches!(err("speed_deg_s", "0.01"), E::OutOfRange { .. }));
        assert!(matches!(err("link_timeout_s", "-2"), E::OutOfRange { .. }));
        assert!(matches!(err("arm_mm", "off"), E::BadNumber { .. }));
        assert!(matches!(
            err("servo1.trim_us", "3000"),
            E::OutOfRange { .. }
        ));
        assert!(matches!(
            err("servo1.dir", "up"),
            E::BadValue {
                expected: Expected::NormalOrReversed,
                ..
            }
        ));
        // In range on its own, but the servo set is inconsistent: home outside its limits.
        assert!(matches!(
            err("servo4.trim_us", "1950"),
            E::BadServoConfig(ServoError::HomeOutsideLimits { servo: 4, .. })
        ));
        assert!(matches!(err("servos.min_us", "1600"), E::BadServoConfig(_)));
        // In range on its own, but no home height exists.
        assert!(matches!(err("rod_mm", "10"), E::BadGeometry(_)));
    }

    #[test]
    fn out_of_range_names_setting_and_limits() {
        assert_eq!(
            parse("frame_hz", "20"),
            Err(SettingError::OutOfRange {
                setting: SettingId::FrameHz,
                value: 20.0,
                min: 50.0,
                max: 333.0,
                unit: "Hz",
                off_allowed: false,
            })
        );
        assert_eq!(
            parse("speed_mm_s", "5000"),
            Err(SettingError::OutOfRange {
                setting: SettingId::SpeedMmS,
                value: 5000.0,
                min: 0.1,
                max: 1000.0,
                unit: "mm/s",
                off_allowed: true,
            })
        );
    }
}
