//! Settings: what a user can change without touching code, their names, ranges and defaults,
//! and a fixed-size binary form for flash.
//!
//! [`Settings`] holds the platform's build numbers (a [`PairedLayout`]), the six servo mappings,
//! the motion limits and the serial settings. `set <name> <value>` changes one value; the
//! controller then validates the whole result ([`Settings::validate`]: every range, the servo
//! set, the geometry) before committing it, so a refused change leaves everything as it was.
//!
//! # Names (as `config` lists them and `set` takes them)
//!
//! | name | value | default |
//! | --- | --- | --- |
//! | `frame_hz` | servo frame rate, whole number 50..=333 Hz | 50 |
//! | `baud` | one of 9600 19200 38400 57600 115200 230400 460800 921600 | 115200 |
//! | `echo` | `on` / `off` (echo and prompt, for terminals) | on |
//! | `speed_mm_s` | linear speed limit 0.1..=1000 mm/s, `0`/`off` = jump | 50 |
//! | `speed_deg_s` | angular speed limit 0.1..=3600 deg/s, `0`/`off` = jump | 60 |
//! | `link_timeout_s` | return home after this long without a command, 0.1..=3600 s, `0`/`off` | off |
//! | `base_radius_mm`, `platform_radius_mm` | joint circle radii, 1..=1000 mm | 75, 60 |
//! | `base_half_angle_deg`, `platform_half_angle_deg` | half the angle within a pair, 0..=60 deg | 20, 20 |
//! | `arm_mm`, `rod_mm` | servo arm `a` 1..=500 mm, rod `s` 1..=2000 mm | 20, 120 |
//! | `servoN.trim_us` | home pulse `W0` of servo N (1..=6), 400..=2600 us | 1500 |
//! | `servoN.rate_us_rad` | servo rate `r`, 100..=5000 us/rad | 1600/pi |
//! | `servoN.dir` | `normal` (even servos, eq. 13) / `reversed` (odd servos, eq. 14) | by parity |
//! | `servoN.min_us`, `servoN.max_us` | pulse limits, 400..=2600 us | 1100, 1900 |
//!
//! `servos.<field>` sets that field of all six servos at once. The `defaults` command restores
//! [`Settings::default`] except `baud` and `echo`, so the host keeps its connection.
//!
//! # Binary form ([`Settings::encode`], [`Settings::decode`])
//!
//! [`ENCODED_LEN`] bytes, little-endian:
//!
//! | offset | size | content |
//! | --- | --- | --- |
//! | 0 | 4 | magic `HXPS` |
//! | 4 | 2 | format version ([`FORMAT_VERSION`]) |
//! | 6 | 2 | payload length ([`PAYLOAD_LEN`]) |
//! | 8 | 2 | `frame_hz` (u16) |
//! | 10 | 4 | `baud` (u32) |
//! | 14 | 1 | `echo` (0 or 1) |
//! | 15 | 1 | reserved, 0 |
//! | 16 | 12 | `speed_mm_s`, `speed_deg_s`, `link_timeout_s` (f32) |
//! | 28 | 24 | layout: base radius, base half angle, platform radius, platform half angle, arm, rod (f32) |
//! | 52 | 6 x 20 | per servo: trim, rate, min, max (f32), direction (0 normal, 1 reversed), 3 reserved 0 |
//! | 172 | 4 | CRC-32 (IEEE 802.3) of bytes 0..172 |
//!
//! Decoding checks magic, version, length, checksum, every enumerated byte and finally
//! [`Settings::validate`], so a decoded `Settings` is always usable.

use core::fmt::{self, Display, Formatter};

use kinematics_core::geometry::PairedLayout;
use kinematics_core::servo::{
    MAX_PULSE_US, MAX_RATE_US_PER_RAD, MIN_PULSE_US, MIN_RATE_US_PER_RAD,
};
use kinematics_core::{Direction, Geometry, ServoConfig, ServoSet, LEGS};

use crate::number::{parse_f32, parse_u32, NumberError};
use crate::report::{word, Error, Field};

/// Lowest servo frame rate, Hz.
pub const FRAME_HZ_MIN: u16 = 50;
/// Highest servo frame rate, Hz (a 3 ms frame still holds the longest pulse).
pub const FRAME_HZ_MAX: u16 = 333;
/// Baud rates the UART may be set to.
pub const BAUD_RATES: [u32; 8] = [
    9_600, 19_200, 38_400, 57_600, 115_200, 230_400, 460_800, 921_600,
];

/// Settings as shipped.
pub const DEFAULT_FRAME_HZ: u16 = 50;
/// Default UART baud rate.
pub const DEFAULT_BAUD: u32 = 115_200;
/// Default linear speed limit, mm/s.
pub const DEFAULT_SPEED_MM_S: f32 = 50.0;
/// Default angular speed limit, deg/s.
pub const DEFAULT_SPEED_DEG_S: f32 = 60.0;

/// Everything configurable.
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
    /// Return home after this long without a command, s; 0 = never.
    pub link_timeout_s: f32,
    /// Servo frame rate, Hz.
    pub frame_hz: u16,
    /// UART baud rate.
    pub baud: u32,
    /// Echo typed characters and show a prompt.
    pub echo: bool,
}

impl Default for Settings {
    fn default() -> Settings {
        Settings {
            layout: PairedLayout::default(),
            servos: ServoSet::default(),
            speed_mm_s: DEFAULT_SPEED_MM_S,
            speed_deg_s: DEFAULT_SPEED_DEG_S,
            link_timeout_s: 0.0,
            frame_hz: DEFAULT_FRAME_HZ,
            baud: DEFAULT_BAUD,
            echo: true,
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

    fn get(self, l: &PairedLayout) -> f32 {
        match self {
            LayoutParam::BaseRadiusMm => l.base_radius_mm,
            LayoutParam::BaseHalfAngleDeg => l.base_half_angle_deg,
            LayoutParam::PlatformRadiusMm => l.platform_radius_mm,
            LayoutParam::PlatformHalfAngleDeg => l.platform_half_angle_deg,
            LayoutParam::ArmMm => l.arm_mm,
            LayoutParam::RodMm => l.rod_mm,
        }
    }

    fn slot(self, l: &mut PairedLayout) -> &mut f32 {
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
}

impl ServoParam {
    /// All, in listing order.
    pub const ALL: [ServoParam; 5] = [
        ServoParam::TrimUs,
        ServoParam::RateUsRad,
        ServoParam::Dir,
        ServoParam::MinUs,
        ServoParam::MaxUs,
    ];

    /// The field name after `servoN.`.
    pub const fn name(self) -> &'static str {
        match self {
            ServoParam::TrimUs => "trim_us",
            ServoParam::RateUsRad => "rate_us_rad",
            ServoParam::Dir => "dir",
            ServoParam::MinUs => "min_us",
            ServoParam::MaxUs => "max_us",
        }
    }

    fn get(self, s: &ServoConfig) -> SettingValue {
        match self {
            ServoParam::TrimUs => SettingValue::Number(s.home_us),
            ServoParam::RateUsRad => SettingValue::Number(s.rate_us_per_rad),
            ServoParam::Dir => SettingValue::Dir(s.direction),
            ServoParam::MinUs => SettingValue::Number(s.min_us),
            ServoParam::MaxUs => SettingValue::Number(s.max_us),
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
    /// `link_timeout_s`.
    LinkTimeoutS,
    /// A build number.
    Layout(LayoutParam),
    /// A servo field.
    Servo(ServoSel, ServoParam),
}

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
    /// `on` / `off`.
    Flag,
    /// `normal` / `reversed`.
    Dir,
}

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
    pub const GLOBAL: [SettingId; 12] = [
        SettingId::FrameHz,
        SettingId::Baud,
        SettingId::Echo,
        SettingId::SpeedMmS,
        SettingId::SpeedDegS,
        SettingId::LinkTimeoutS,
        SettingId::Layout(LayoutParam::BaseRadiusMm),
        SettingId::Layout(LayoutParam::BaseHalfAngleDeg),
        SettingId::Layout(LayoutParam::PlatformRadiusMm),
        SettingId::Layout(LayoutParam::PlatformHalfAngleDeg),
        SettingId::Layout(LayoutParam::ArmMm),
        SettingId::Layout(LayoutParam::RodMm),
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
            SettingId::LinkTimeoutS => "link_timeout_s",
            SettingId::Layout(p) => p.name(),
            SettingId::Servo(..) => return None,
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
            SettingId::LinkTimeoutS => number_or_off(0.1, 3600.0, "s"),
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
            },
        }
    }

    /// Parses and range-checks a value typed for this setting (already lowercase).
    pub fn parse_value(self, text: &str) -> Result<SettingValue, Error> {
        let field = Field::Setting(self);
        let number_error = |e: NumberError| match e {
            NumberError::Syntax => Error::BadNumber {
                field,
                word: word(text),
            },
            NumberError::NotFinite => Error::NotFinite {
                field,
                word: word(text),
            },
            NumberError::TooLarge => Error::NumberTooLarge {
                field,
                word: word(text),
            },
            NumberError::NotWhole => Error::BadValue {
                setting: self,
                word: word(text),
                expected: "a whole number",
            },
        };
        let bad_value = |expected| Error::BadValue {
            setting: self,
            word: word(text),
            expected,
        };
        let value = match self.kind() {
            Kind::Whole { .. } => SettingValue::Whole(parse_u32(text).map_err(number_error)?),
            Kind::Number { off_allowed, .. } => {
                if off_allowed && text == "off" {
                    SettingValue::Number(0.0)
                } else {
                    SettingValue::Number(parse_f32(text).map_err(number_error)?)
                }
            }
            Kind::Flag => match text {
                "on" | "1" => SettingValue::Flag(true),
                "off" | "0" => SettingValue::Flag(false),
                _ => return Err(bad_value("on or off")),
            },
            Kind::Dir => match text {
                "normal" | "+1" | "1" => SettingValue::Dir(Direction::Normal),
                "reversed" | "-1" => SettingValue::Dir(Direction::Reversed),
                _ => return Err(bad_value("normal or reversed")),
            },
        };
        self.check(value)?;
        Ok(value)
    }

    /// Checks that a value has this setting's form and range.
    pub fn check(self, value: SettingValue) -> Result<(), Error> {
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
                    if list.contains(&v) {
                        return Ok(());
                    }
                    let mut text = heapless::String::<12>::new();
                    let _ = fmt::write(&mut text, format_args!("{v}"));
                    return Err(Error::BadValue {
                        setting: self,
                        word: word(&text),
                        expected: "one of 9600 19200 38400 57600 115200 230400 460800 921600",
                    });
                }
                if (min..=max).contains(&v) {
                    Ok(())
                } else {
                    Err(Error::OutOfRange {
                        setting: self,
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
                    Err(Error::OutOfRange {
                        setting: self,
                        value: v,
                        min,
                        max,
                        unit,
                        off_allowed,
                    })
                }
            }
            (Kind::Flag, SettingValue::Flag(_)) | (Kind::Dir, SettingValue::Dir(_)) => Ok(()),
            _ => Err(Error::BadValue {
                setting: self,
                word: word("?"),
                expected: "a value of the right kind",
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
    /// The current value of a setting (`servos.x` reads servo 1).
    pub fn get(&self, id: SettingId) -> SettingValue {
        match id {
            SettingId::FrameHz => SettingValue::Whole(u32::from(self.frame_hz)),
            SettingId::Baud => SettingValue::Whole(self.baud),
            SettingId::Echo => SettingValue::Flag(self.echo),
            SettingId::SpeedMmS => SettingValue::Number(self.speed_mm_s),
            SettingId::SpeedDegS => SettingValue::Number(self.speed_deg_s),
            SettingId::LinkTimeoutS => SettingValue::Number(self.link_timeout_s),
            SettingId::Layout(p) => SettingValue::Number(p.get(&self.layout)),
            SettingId::Servo(sel, p) => {
                let index = match sel {
                    ServoSel::One(n) => usize::from(n).saturating_sub(1).min(LEGS - 1),
                    ServoSel::All => 0,
                };
                p.get(&self.servos.0[index])
            }
        }
    }

    /// A copy with one value replaced (not validated: see [`Settings::validate`]). A value of
    /// the wrong kind for the setting leaves it unchanged.
    pub fn with(&self, id: SettingId, value: SettingValue) -> Settings {
        let mut s = *self;
        match (id, value) {
            (SettingId::FrameHz, SettingValue::Whole(v)) => {
                s.frame_hz = u16::try_from(v).unwrap_or(u16::MAX)
            }
            (SettingId::Baud, SettingValue::Whole(v)) => s.baud = v,
            (SettingId::Echo, SettingValue::Flag(v)) => s.echo = v,
            (SettingId::SpeedMmS, SettingValue::Number(v)) => s.speed_mm_s = v,
            (SettingId::SpeedDegS, SettingValue::Number(v)) => s.speed_deg_s = v,
            (SettingId::LinkTimeoutS, SettingValue::Number(v)) => s.link_timeout_s = v,
            (SettingId::Layout(p), SettingValue::Number(v)) => *p.slot(&mut s.layout) = v,
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

    /// Checks every value's range, the servo set and the geometry; returns the geometry.
    pub fn validate(&self) -> Result<Geometry, Error> {
        for id in SettingId::GLOBAL {
            id.check(self.get(id))?;
        }
        for servo in 1..=LEGS as u8 {
            for p in ServoParam::ALL {
                let id = SettingId::Servo(ServoSel::One(servo), p);
                id.check(self.get(id))?;
            }
        }
        self.servos.validate().map_err(Error::BadServoConfig)?;
        self.layout.build().map_err(Error::BadGeometry)
    }
}

/// Binary format version.
pub const FORMAT_VERSION: u16 = 1;
/// Bytes between the header and the checksum.
pub const PAYLOAD_LEN: usize = 164;
/// Bytes of an encoded [`Settings`].
pub const ENCODED_LEN: usize = HEADER_LEN + PAYLOAD_LEN + 4;
const HEADER_LEN: usize = 8;
const MAGIC: [u8; 4] = *b"HXPS";
const SERVO_RECORD_LEN: usize = 20;

/// Why stored bytes are not a usable [`Settings`].
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    /// Fewer than [`ENCODED_LEN`] bytes.
    TooShort,
    /// Not settings at all (erased flash reads as `0xFF`).
    BadMagic,
    /// Written by a different format version.
    UnsupportedVersion(u16),
    /// The stored payload length does not match this version's.
    BadLength(u16),
    /// The checksum does not match: the data is damaged.
    BadChecksum,
    /// A byte that must be 0/1 (echo, direction) or reserved 0 is not.
    BadField {
        /// Offset of the byte.
        offset: usize,
    },
    /// Intact, but the values are not valid settings.
    Invalid(Error),
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), bit by bit: small and fast enough
/// for a 176-byte record.
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = 0xFFFF_FFFFu32;
    for &b in bytes {
        crc ^= u32::from(b);
        for _ in 0..8 {
            let mask = (crc & 1).wrapping_neg();
            crc = (crc >> 1) ^ (0xEDB8_8320 & mask);
        }
    }
    !crc
}

struct Writer<'a> {
    buf: &'a mut [u8; ENCODED_LEN],
    at: usize,
}

impl Writer<'_> {
    fn bytes(&mut self, b: &[u8]) {
        self.buf[self.at..self.at + b.len()].copy_from_slice(b);
        self.at += b.len();
    }
    fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }
}

struct Reader<'a> {
    buf: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take<const N: usize>(&mut self) -> [u8; N] {
        let mut out = [0u8; N];
        out.copy_from_slice(&self.buf[self.at..self.at + N]);
        self.at += N;
        out
    }
    fn u8(&mut self) -> u8 {
        self.take::<1>()[0]
    }
    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.take())
    }
    /// A byte that must be 0 or 1.
    fn bit(&mut self) -> Result<bool, DecodeError> {
        let offset = self.at;
        match self.u8() {
            0 => Ok(false),
            1 => Ok(true),
            _ => Err(DecodeError::BadField { offset }),
        }
    }
    fn zeros(&mut self, n: usize) -> Result<(), DecodeError> {
        for _ in 0..n {
            let offset = self.at;
            if self.u8() != 0 {
                return Err(DecodeError::BadField { offset });
            }
        }
        Ok(())
    }
}

impl Settings {
    /// The fixed-size binary form (see the module docs).
    pub fn encode(&self) -> [u8; ENCODED_LEN] {
        let mut buf = [0u8; ENCODED_LEN];
        let mut w = Writer {
            buf: &mut buf,
            at: 0,
        };
        w.bytes(&MAGIC);
        w.bytes(&FORMAT_VERSION.to_le_bytes());
        w.bytes(&(PAYLOAD_LEN as u16).to_le_bytes());
        w.bytes(&self.frame_hz.to_le_bytes());
        w.bytes(&self.baud.to_le_bytes());
        w.bytes(&[u8::from(self.echo), 0]);
        w.f32(self.speed_mm_s);
        w.f32(self.speed_deg_s);
        w.f32(self.link_timeout_s);
        for p in LayoutParam::ALL {
            w.f32(p.get(&self.layout));
        }
        for s in &self.servos.0 {
            w.f32(s.home_us);
            w.f32(s.rate_us_per_rad);
            w.f32(s.min_us);
            w.f32(s.max_us);
            let dir = match s.direction {
                Direction::Normal => 0,
                Direction::Reversed => 1,
            };
            w.bytes(&[dir, 0, 0, 0]);
        }
        let end = w.at;
        debug_assert_eq!(end, HEADER_LEN + PAYLOAD_LEN);
        let crc = crc32(&buf[..end]);
        buf[end..].copy_from_slice(&crc.to_le_bytes());
        buf
    }

    /// Reads the binary form back, refusing anything damaged, foreign or invalid.
    pub fn decode(bytes: &[u8]) -> Result<Settings, DecodeError> {
        if bytes.len() < ENCODED_LEN {
            return Err(DecodeError::TooShort);
        }
        let bytes = &bytes[..ENCODED_LEN];
        if bytes[..4] != MAGIC {
            return Err(DecodeError::BadMagic);
        }
        let version = u16::from_le_bytes([bytes[4], bytes[5]]);
        if version != FORMAT_VERSION {
            return Err(DecodeError::UnsupportedVersion(version));
        }
        let len = u16::from_le_bytes([bytes[6], bytes[7]]);
        if usize::from(len) != PAYLOAD_LEN {
            return Err(DecodeError::BadLength(len));
        }
        let end = HEADER_LEN + PAYLOAD_LEN;
        let stored =
            u32::from_le_bytes([bytes[end], bytes[end + 1], bytes[end + 2], bytes[end + 3]]);
        if crc32(&bytes[..end]) != stored {
            return Err(DecodeError::BadChecksum);
        }
        let mut r = Reader {
            buf: bytes,
            at: HEADER_LEN,
        };
        let frame_hz = u16::from_le_bytes(r.take());
        let baud = u32::from_le_bytes(r.take());
        let echo = r.bit()?;
        r.zeros(1)?;
        let speed_mm_s = r.f32();
        let speed_deg_s = r.f32();
        let link_timeout_s = r.f32();
        let mut layout = PairedLayout::default();
        for p in LayoutParam::ALL {
            *p.slot(&mut layout) = r.f32();
        }
        let mut servos = ServoSet::default();
        for s in servos.0.iter_mut() {
            s.home_us = r.f32();
            s.rate_us_per_rad = r.f32();
            s.min_us = r.f32();
            s.max_us = r.f32();
            s.direction = if r.bit()? {
                Direction::Reversed
            } else {
                Direction::Normal
            };
            r.zeros(SERVO_RECORD_LEN - 17)?;
        }
        let settings = Settings {
            layout,
            servos,
            speed_mm_s,
            speed_deg_s,
            link_timeout_s,
            frame_hz,
            baud,
            echo,
        };
        settings.validate().map_err(DecodeError::Invalid)?;
        Ok(settings)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::report::Code;

    fn parse(name: &str, value: &str) -> Result<Settings, Error> {
        let id = SettingId::parse(name).expect("known name");
        let s = Settings::default().with(id, id.parse_value(value)?);
        s.validate()?;
        Ok(s)
    }

    #[test]
    fn defaults_are_valid_and_as_documented() {
        let s = Settings::default();
        s.validate().unwrap();
        assert_eq!((s.frame_hz, s.baud, s.echo), (50, 115_200, true));
        assert_eq!(s.link_timeout_s, 0.0);
        assert_eq!(s.servos, ServoSet::default());
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
        assert_eq!(parse("baud", "921600").unwrap().baud, 921_600);
        assert!(!parse("echo", "off").unwrap().echo);
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
    }

    #[test]
    fn bad_values_are_refused_with_their_own_codes() {
        let code = |name, value| parse(name, value).unwrap_err().code();
        assert_eq!(code("frame_hz", "49"), Code::OutOfRange);
        assert_eq!(code("frame_hz", "334"), Code::OutOfRange);
        assert_eq!(code("frame_hz", "50.5"), Code::BadValue);
        assert_eq!(code("frame_hz", "fast"), Code::BadNumber);
        assert_eq!(code("frame_hz", "99999999999"), Code::NumberTooLarge);
        assert_eq!(code("baud", "1000000"), Code::BadValue);
        assert_eq!(code("echo", "maybe"), Code::BadValue);
        assert_eq!(code("speed_mm_s", "-1"), Code::OutOfRange);
        assert_eq!(code("speed_mm_s", "nan"), Code::NotFinite);
        assert_eq!(code("speed_mm_s", "1e39"), Code::NumberTooLarge);
        assert_eq!(code("speed_deg_s", "0.01"), Code::OutOfRange);
        assert_eq!(code("link_timeout_s", "-2"), Code::OutOfRange);
        assert_eq!(code("arm_mm", "off"), Code::BadNumber);
        assert_eq!(code("servo1.trim_us", "3000"), Code::OutOfRange);
        assert_eq!(code("servo1.dir", "up"), Code::BadValue);
        // In range on its own, but the servo set is inconsistent: home outside its limits.
        assert_eq!(code("servo4.trim_us", "1950"), Code::BadServoConfig);
        assert_eq!(code("servos.min_us", "1600"), Code::BadServoConfig);
        // In range on its own, but no home height exists.
        assert_eq!(code("rod_mm", "10"), Code::BadGeometry);
    }

    #[test]
    fn out_of_range_message_names_setting_and_limits() {
        let e = parse("frame_hz", "20").unwrap_err();
        assert_eq!(std::format!("{e}"), "frame_hz 20 is outside 50..333 Hz");
        let e = parse("speed_mm_s", "5000").unwrap_err();
        assert_eq!(
            std::format!("{e}"),
            "speed_mm_s 5000 is outside 0.1..1000 mm/s (or 0/off)"
        );
    }

    #[test]
    fn encoding_roundtrips() {
        let mut s = Settings {
            frame_hz: 200,
            baud: 921_600,
            echo: false,
            speed_mm_s: 0.0,
            speed_deg_s: 12.5,
            link_timeout_s: 3.0,
            ..Settings::default()
        };
        s.layout.rod_mm = 125.0;
        s.servos.0[4].home_us = 1523.25;
        s.servos.0[0].direction = Direction::Normal;
        s.servos.0[5].min_us = 1000.0;
        s.validate().unwrap();
        let bytes = s.encode();
        assert_eq!(bytes.len(), ENCODED_LEN);
        assert_eq!(&bytes[..4], b"HXPS");
        assert_eq!(Settings::decode(&bytes), Ok(s));
        assert_eq!(
            Settings::decode(&Settings::default().encode()),
            Ok(Settings::default())
        );
        // Trailing bytes (a flash page) are ignored.
        let mut page = [0xFFu8; 256];
        page[..ENCODED_LEN].copy_from_slice(&bytes);
        assert_eq!(Settings::decode(&page), Ok(s));
    }

    #[test]
    fn checksum_is_standard_crc32() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn any_single_bit_flip_is_rejected() {
        let bytes = Settings::default().encode();
        for i in 0..ENCODED_LEN {
            for bit in 0..8 {
                let mut damaged = bytes;
                damaged[i] ^= 1 << bit;
                assert!(Settings::decode(&damaged).is_err(), "byte {i} bit {bit}");
            }
        }
    }

    #[test]
    fn foreign_and_short_data_are_rejected() {
        assert_eq!(
            Settings::decode(&[0xFF; ENCODED_LEN]),
            Err(DecodeError::BadMagic)
        );
        assert_eq!(Settings::decode(&[0; 10]), Err(DecodeError::TooShort));
        let mut bytes = Settings::default().encode();
        bytes[4] = 2;
        assert_eq!(
            Settings::decode(&bytes),
            Err(DecodeError::UnsupportedVersion(2))
        );
        let mut bytes = Settings::default().encode();
        bytes[6] = 1;
        assert!(matches!(
            Settings::decode(&bytes),
            Err(DecodeError::BadLength(_))
        ));
    }

    /// Re-seals damaged contents with a correct checksum, as a buggy writer would.
    fn reseal(mut bytes: [u8; ENCODED_LEN]) -> [u8; ENCODED_LEN] {
        let end = HEADER_LEN + PAYLOAD_LEN;
        let crc = crc32(&bytes[..end]);
        bytes[end..].copy_from_slice(&crc.to_le_bytes());
        bytes
    }

    #[test]
    fn intact_but_invalid_contents_are_rejected() {
        let mut bytes = Settings::default().encode();
        bytes[8..10].copy_from_slice(&10u16.to_le_bytes()); // frame_hz 10
        assert!(matches!(
            Settings::decode(&reseal(bytes)),
            Err(DecodeError::Invalid(Error::OutOfRange {
                setting: SettingId::FrameHz,
                ..
            }))
        ));
        let mut bytes = Settings::default().encode();
        bytes[16..20].copy_from_slice(&f32::NAN.to_le_bytes()); // speed NaN
        assert!(matches!(
            Settings::decode(&reseal(bytes)),
            Err(DecodeError::Invalid(_))
        ));
        let mut bytes = Settings::default().encode();
        bytes[14] = 7; // echo must be 0 or 1
        assert_eq!(
            Settings::decode(&reseal(bytes)),
            Err(DecodeError::BadField { offset: 14 })
        );
        let mut bytes = Settings::default().encode();
        bytes[52 + 16] = 2; // servo 1 direction
        assert_eq!(
            Settings::decode(&reseal(bytes)),
            Err(DecodeError::BadField { offset: 68 })
        );
        let mut bytes = Settings::default().encode();
        bytes[28 + 20..28 + 24].copy_from_slice(&5.0f32.to_le_bytes()); // rod 5 mm
        assert!(matches!(
            Settings::decode(&reseal(bytes)),
            Err(DecodeError::Invalid(Error::BadGeometry(_)))
        ));
    }

    proptest::proptest! {
        #[test]
        fn decoding_arbitrary_bytes_never_panics(bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..300)) {
            if let Ok(s) = Settings::decode(&bytes) {
                proptest::prop_assert!(s.validate().is_ok());
            }
        }
    }
}
