//! The settings record: [`Settings`], UART0's baud rate and the number of the save as a
//! fixed-size, versioned, checksummed block of bytes for flash, and back. Which flash sector it goes to is
//! [`crate::store`]'s business; writing it is the board's.
//!
//! [`ENCODED_LEN`] bytes, little-endian (format version [`FORMAT_VERSION`]):
//!
//! | offset | size | content |
//! | --- | --- | --- |
//! | 0 | 4 | magic `HXPS` |
//! | 4 | 2 | format version |
//! | 6 | 2 | payload length ([`PAYLOAD_LEN`]) |
//! | 8 | 2 | `frame_hz` (u16) |
//! | 10 | 2 | `stream.max_step_pct` (u16, tenths of a percent, 0 off; 0 in records written before it) |
//! | 12 | 12 | `speed_mm_s`, `speed_deg_s`, `link_timeout_s` (f32) |
//! | 24 | 24 | layout (f32): base radius, base half angle, platform radius and half angle, a, s |
//! | 48 | 6 x 20 | per servo: trim, rate, min, max (f32), dir (0 normal, 1 reversed), speed rating (u8, hundredths of a second per 60 degrees, 0 not rated), torque rating (u16, hundredths of a kgf cm, 0 not rated) |
//! | 168 | 8 | `accel_mm_s2`, `accel_deg_s2` (f32) |
//! | 176 | 24 | stream full scales x, y, z (mm), roll, pitch, yaw (deg) (f32) |
//! | 200 | 1 | `stream.bits` |
//! | 201 | 6 | `stream.axis1..6`: 0..=5 x y z roll pitch yaw, 6 none |
//! | 207 | 1 | `estop_pin`: GPIO, `0xFF` off |
//! | 208 | 1 | `estop_action`: 0 freeze, 1 home |
//! | 209 | 1 | `power_pin`: GPIO, `0xFF` off |
//! | 210 | 2 | reserved, 0 |
//! | 212 | 4 | `payload_g` (f32) |
//! | 216 | 12 | `payload_com_x_mm`, `payload_com_y_mm`, `payload_com_z_mm` (f32) |
//! | 228 | 4 | `baud`: UART0's baud rate (u32, one of [`BAUD_RATES`]) |
//! | 232 | 12 | `pivot_x_mm`, `pivot_y_mm`, `pivot_z_mm` (f32) |
//! | 244 | 4 | sequence number of the save (u32; the newer of two records has the higher one) |
//! | 248 | 4 | CRC-32 (IEEE 802.3) of bytes 0..248 |
//!
//! The whole record fits one 256-byte flash page.
//!
//! Format 4, which boards in the field hold, is read too: the same bytes up to 232, each servo's
//! speed rating byte (offset 17 of its block) then reserved, 0, and without the pivot (payload
//! length 224, the sequence number at 232, the CRC-32 of bytes 0..236 at 236): its servos are
//! not rated for speed and its pivot is the platform frame's origin (0, 0, 0), where every
//! board of format 4 turned.
//!
//! Format 3, which boards in the field hold, is read too: the same bytes up to 228, without
//! `baud` and the pivot (payload length 220, the sequence number at 228, the CRC-32 of bytes 0..232 at 232).
//! Its baud rate is [`DEFAULT_BAUD`], the rate every board of format 3 came up at, and its
//! pivot the origin. (The
//! payload and the torque ratings joined format 3 before any board had a format-3 record in
//! its flash, so every format-3 record ever written has them.)
//!
//! The sequence number and the checksum come last, so a write that stops anywhere before its
//! end leaves a record whose checksum does not match (a flash page is programmed from its first
//! byte to its last).
//!
//! Of the link settings only `baud` is in it (a sim rig streams to UART0 at its saved rate from
//! power-up on, with no command first). `echo` is not: it belongs to the link a person types on,
//! and the USB port always answers, with echo on, whatever UART0's rate, so a forgotten rate
//! locks no one out. Decoding checks magic, version, length, checksum, every enumerated byte and finally
//! [`Settings::validate`], so decoded settings are always usable.

use kinematics_core::pose::Axis;
use kinematics_core::{Direction, Libm, Math, ServoSet};

use crate::payload::hundredths;
use crate::safety::EstopAction;
use crate::servo_speed;
use crate::settings::{LayoutParam, SettingError, Settings, BAUD_RATES, DEFAULT_BAUD};
use crate::stream::step_tenths;

/// Binary format version written (1 also held the link settings, 2 had no sequence number and
/// none of the acceleration, stream and safety settings; neither was ever written to a board's
/// flash; 3 gained the payload and the torque ratings before any board had it, and is still
/// read; 4 added `baud`, and is still read; 5 the pivot and the servos' speed ratings: see the
/// module docs).
pub const FORMAT_VERSION: u16 = 5;
/// An older format still read: no pivot, no speed ratings.
pub const FORMAT_VERSION_NO_PIVOT: u16 = 4;
/// The oldest format still read (boards in the field hold it): no `baud`, no pivot, no speed
/// ratings.
pub const FORMAT_VERSION_NO_BAUD: u16 = 3;
/// Bytes of settings between the header and the sequence number.
pub const PAYLOAD_LEN: usize = 236;
/// [`PAYLOAD_LEN`] of format 4 (no pivot; the speed byte reserved).
const PAYLOAD_LEN_NO_PIVOT: usize = PAYLOAD_LEN - 12;
/// [`PAYLOAD_LEN`] of format 3 (no `baud`, no pivot).
const PAYLOAD_LEN_NO_BAUD: usize = PAYLOAD_LEN_NO_PIVOT - 4;
/// A pin byte meaning "off".
const PIN_OFF: u8 = 0xFF;
/// A `stream.axisN` byte meaning `none`.
const AXIS_NONE: u8 = 6;
/// Bytes of an encoded [`Record`].
pub const ENCODED_LEN: usize = HEADER_LEN + PAYLOAD_LEN + 4 + 4;
/// Offset of the sequence number.
pub const SEQUENCE_OFFSET: usize = HEADER_LEN + PAYLOAD_LEN;
/// Offset of the CRC-32, the last four bytes.
pub const CRC_OFFSET: usize = SEQUENCE_OFFSET + 4;
const HEADER_LEN: usize = 8;
const MAGIC: [u8; 4] = *b"HXPS";
const SERVO_RECORD_LEN: usize = 20;
const LEGS_LEN: usize = kinematics_core::LEGS;

/// One saved copy of the platform's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    /// Which save this is: each save numbers its record one higher than the newest before it
    /// (wrapping; see [`is_newer`]).
    pub sequence: u32,
    /// The settings saved.
    pub settings: Settings,
    /// UART0's baud rate saved (one of [`BAUD_RATES`]).
    pub baud: u32,
}

/// Whether sequence number `a` is newer than `b`: `a` follows `b` by less than half the
/// number range, so the order survives the wrap from `u32::MAX` to 0.
pub fn is_newer(a: u32, b: u32) -> bool {
    (a.wrapping_sub(b) as i32) > 0
}

/// Why stored bytes are not a usable [`Record`].
#[derive(Debug, Clone, PartialEq)]
pub enum DecodeError {
    /// Fewer bytes than a record of its format has.
    TooShort,
    /// Not settings at all (erased flash reads as `0xFF`).
    BadMagic,
    /// Written by a different format version.
    UnsupportedVersion(u16),
    /// The stored payload length does not match this version's.
    BadLength(u16),
    /// The checksum does not match: the data is damaged.
    BadChecksum,
    /// A byte that must be 0/1 (direction) or reserved 0 is not, or a baud rate that is not
    /// one of [`BAUD_RATES`] (at the offset of its first byte).
    BadField {
        /// Offset of the byte.
        offset: usize,
    },
    /// Intact, but the values are not valid settings.
    Invalid(SettingError),
}

/// CRC-32 (IEEE 802.3, reflected, polynomial 0xEDB88320), bit by bit: small and fast enough
/// for a 248-byte record.
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
    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.take())
    }
    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.take())
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

/// The bytes of `record` (see the module docs).
pub fn encode(record: &Record) -> [u8; ENCODED_LEN] {
    let settings = &record.settings;
    let mut buf = [0u8; ENCODED_LEN];
    let mut w = Writer {
        buf: &mut buf,
        at: 0,
    };
    w.bytes(&MAGIC);
    w.bytes(&FORMAT_VERSION.to_le_bytes());
    w.bytes(&(PAYLOAD_LEN as u16).to_le_bytes());
    w.bytes(&settings.frame_hz.to_le_bytes());
    // Kept to tenths (crate::stream): exact.
    w.bytes(&step_tenths(settings.stream.max_step_pct).to_le_bytes());
    w.f32(settings.speed_mm_s);
    w.f32(settings.speed_deg_s);
    w.f32(settings.link_timeout_s);
    for p in LayoutParam::ALL {
        w.f32(p.get(&settings.layout));
    }
    for ((s, rating), speed) in settings
        .servos
        .0
        .iter()
        .zip(settings.payload.torque_kgcm)
        .zip(settings.servo_speed.s_per_60deg)
    {
        w.f32(s.home_us);
        w.f32(s.rate_us_per_rad);
        w.f32(s.min_us);
        w.f32(s.max_us);
        let dir = match s.direction {
            Direction::Normal => 0,
            Direction::Reversed => 1,
        };
        // Speed ratings are kept to hundredths (crate::servo_speed): exact.
        w.bytes(&[dir, servo_speed::hundredths(speed)]);
        // Ratings are kept to hundredths (crate::payload): exact.
        w.bytes(&hundredths(rating).to_le_bytes());
    }
    w.f32(settings.accel_mm_s2);
    w.f32(settings.accel_deg_s2);
    for v in settings.stream.full_scale {
        w.f32(v);
    }
    w.bytes(&[settings.stream.text_bits]);
    for axis in settings.stream.text_order {
        w.bytes(&[axis.map_or(AXIS_NONE, |a| a as u8)]);
    }
    let safety = &settings.safety;
    let action = match safety.estop_action {
        EstopAction::Freeze => 0,
        EstopAction::Home => 1,
    };
    w.bytes(&[
        safety.estop_pin.unwrap_or(PIN_OFF),
        action,
        safety.power_pin.unwrap_or(PIN_OFF),
        0,
        0,
    ]);
    w.f32(settings.payload.mass_g);
    for v in settings.payload.com_mm {
        w.f32(v);
    }
    w.bytes(&record.baud.to_le_bytes());
    for v in settings.pivot_mm {
        w.f32(v);
    }
    debug_assert_eq!(w.at, SEQUENCE_OFFSET);
    w.bytes(&record.sequence.to_le_bytes());
    let crc = crc32(&buf[..CRC_OFFSET]);
    buf[CRC_OFFSET..].copy_from_slice(&crc.to_le_bytes());
    buf
}

/// Reads a record back (trailing bytes are ignored), refusing anything damaged, foreign or
/// invalid.
pub fn decode(bytes: &[u8]) -> Result<Record, DecodeError> {
    decode_with::<Libm>(bytes)
}

/// [`decode`], the settings' geometry validated with `M`'s maths (the board's own, so that it
/// need not carry `libm` for this alone).
pub fn decode_with<M: Math>(bytes: &[u8]) -> Result<Record, DecodeError> {
    // The shorter of the two formats read.
    if bytes.len() < HEADER_LEN + PAYLOAD_LEN_NO_BAUD + 8 {
        return Err(DecodeError::TooShort);
    }
    if bytes[..4] != MAGIC {
        return Err(DecodeError::BadMagic);
    }
    let version = u16::from_le_bytes([bytes[4], bytes[5]]);
    let payload_len = match version {
        FORMAT_VERSION => PAYLOAD_LEN,
        FORMAT_VERSION_NO_PIVOT => PAYLOAD_LEN_NO_PIVOT,
        FORMAT_VERSION_NO_BAUD => PAYLOAD_LEN_NO_BAUD,
        _ => return Err(DecodeError::UnsupportedVersion(version)),
    };
    let len = u16::from_le_bytes([bytes[6], bytes[7]]);
    if usize::from(len) != payload_len {
        return Err(DecodeError::BadLength(len));
    }
    let sequence_offset = HEADER_LEN + payload_len;
    let crc_offset = sequence_offset + 4;
    if bytes.len() < crc_offset + 4 {
        return Err(DecodeError::TooShort);
    }
    let le32 =
        |at: usize| u32::from_le_bytes([bytes[at], bytes[at + 1], bytes[at + 2], bytes[at + 3]]);
    if crc32(&bytes[..crc_offset]) != le32(crc_offset) {
        return Err(DecodeError::BadChecksum);
    }
    let mut r = Reader {
        buf: bytes,
        at: HEADER_LEN,
    };
    let frame_hz = u16::from_le_bytes(r.take());
    let max_step_tenths = r.u16();
    let speed_mm_s = r.f32();
    let speed_deg_s = r.f32();
    let link_timeout_s = r.f32();
    let mut settings = Settings {
        servos: ServoSet::default(),
        speed_mm_s,
        speed_deg_s,
        link_timeout_s,
        frame_hz,
        ..Settings::default()
    };
    for p in LayoutParam::ALL {
        *p.slot(&mut settings.layout) = r.f32();
    }
    for ((s, rating), speed) in settings
        .servos
        .0
        .iter_mut()
        .zip(settings.payload.torque_kgcm.iter_mut())
        .zip(settings.servo_speed.s_per_60deg.iter_mut())
    {
        s.home_us = r.f32();
        s.rate_us_per_rad = r.f32();
        s.min_us = r.f32();
        s.max_us = r.f32();
        s.direction = if r.bit()? {
            Direction::Reversed
        } else {
            Direction::Normal
        };
        if version == FORMAT_VERSION {
            *speed = f32::from(r.u8()) / 100.0;
        } else {
            r.zeros(1)?; // reserved before format 5: not rated
        }
        *rating = f32::from(r.u16()) / 100.0;
    }
    debug_assert_eq!(r.at, HEADER_LEN + 40 + LEGS_LEN * SERVO_RECORD_LEN);
    settings.accel_mm_s2 = r.f32();
    settings.accel_deg_s2 = r.f32();
    for v in settings.stream.full_scale.iter_mut() {
        *v = r.f32();
    }
    settings.stream.text_bits = r.u8();
    settings.stream.max_step_pct = f32::from(max_step_tenths) / 10.0;
    for slot in settings.stream.text_order.iter_mut() {
        let offset = r.at;
        *slot = match r.u8() {
            AXIS_NONE => None,
            i => Some(
                *Axis::ALL
                    .get(usize::from(i))
                    .ok_or(DecodeError::BadField { offset })?,
            ),
        };
    }
    let pin = |b: u8| (b != PIN_OFF).then_some(b);
    settings.safety.estop_pin = pin(r.u8());
    let offset = r.at;
    settings.safety.estop_action = match r.u8() {
        0 => EstopAction::Freeze,
        1 => EstopAction::Home,
        _ => return Err(DecodeError::BadField { offset }),
    };
    settings.safety.power_pin = pin(r.u8());
    r.zeros(2)?;
    settings.payload.mass_g = r.f32();
    for v in settings.payload.com_mm.iter_mut() {
        *v = r.f32();
    }
    let baud = if version == FORMAT_VERSION_NO_BAUD {
        DEFAULT_BAUD
    } else {
        let offset = r.at;
        let baud = r.u32();
        if !BAUD_RATES.contains(&baud) {
            return Err(DecodeError::BadField { offset });
        }
        baud
    };
    if version == FORMAT_VERSION {
        for v in settings.pivot_mm.iter_mut() {
            *v = r.f32();
        }
    }
    debug_assert_eq!(r.at, sequence_offset);
    settings
        .validate_with::<M>()
        .map_err(DecodeError::Invalid)?;
    Ok(Record {
        sequence: le32(sequence_offset),
        settings,
        baud,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn record(sequence: u32, settings: Settings) -> Record {
        Record {
            sequence,
            settings,
            baud: DEFAULT_BAUD,
        }
    }

    fn default_bytes() -> [u8; ENCODED_LEN] {
        encode(&record(7, Settings::default()))
    }

    #[test]
    fn encoding_roundtrips() {
        let mut s = Settings {
            frame_hz: 200,
            speed_mm_s: 0.0,
            speed_deg_s: 12.5,
            link_timeout_s: 3.0,
            ..Settings::default()
        };
        s.layout.rod_mm = 125.0;
        s.servos.0[4].home_us = 1523.25;
        s.servos.0[0].direction = Direction::Normal;
        s.servos.0[5].min_us = 1000.0;
        s.accel_mm_s2 = 500.0;
        s.accel_deg_s2 = 0.0;
        s.stream.full_scale = [10.0, -20.0, 5.5, 0.0, -30.0, 45.0];
        s.stream.text_bits = 12;
        s.stream.max_step_pct = 7.3;
        s.stream.text_order = [
            Some(Axis::Roll),
            None,
            Some(Axis::Z),
            Some(Axis::X),
            Some(Axis::Yaw),
            Some(Axis::Pitch),
        ];
        s.safety.estop_pin = Some(15);
        s.safety.estop_action = EstopAction::Home;
        s.safety.power_pin = Some(22);
        s.payload.mass_g = 1234.5;
        s.payload.com_mm = [-3.0, 4.25, 60.0];
        s.payload.torque_kgcm = [0.0, 2.51, 600.0, 0.01, 12.0, 0.0];
        s.pivot_mm = [12.5, -3.0, 250.0];
        s.servo_speed.s_per_60deg = [0.1, 0.0, 2.55, 0.01, 0.13, 0.2];
        s.validate().unwrap();
        let saved = Record {
            baud: 921_600,
            ..record(0xDEAD_BEEF, s)
        };
        let bytes = encode(&saved);
        assert_eq!(bytes.len(), 252);
        assert!(bytes.len() <= crate::store::PAGE_BYTES, "one flash page");
        assert_eq!(&bytes[..4], b"HXPS");
        assert_eq!(&bytes[4..8], &[5, 0, 236, 0], "format 5, payload 236 bytes");
        // The baud rate, the pivot and the sequence number at their documented places,
        // little-endian.
        assert_eq!(&bytes[228..232], &[0x00, 0x10, 0x0E, 0x00]);
        assert_eq!(&bytes[232..236], &12.5f32.to_le_bytes());
        assert_eq!(&bytes[236..240], &(-3.0f32).to_le_bytes());
        assert_eq!(&bytes[240..244], &250.0f32.to_le_bytes());
        assert_eq!(&bytes[244..248], &[0xEF, 0xBE, 0xAD, 0xDE]);
        assert_eq!(&bytes[248..252], &crc32(&bytes[..248]).to_le_bytes());
        // Servo 2's rating, 2.51 kgf cm, in hundredths at offset 48 + 20 + 18.
        assert_eq!(&bytes[86..88], &251u16.to_le_bytes());
        // Speed ratings in hundredths of a second at offset 17 of each servo's block.
        let speeds: Vec<u8> = (0..6).map(|i| bytes[48 + 20 * i + 17]).collect();
        assert_eq!(speeds, [10, 0, 255, 1, 13, 20]);
        assert_eq!(&bytes[212..216], &1234.5f32.to_le_bytes());
        assert_eq!(decode(&bytes), Ok(saved));
        assert_eq!(
            decode(&encode(&record(0, Settings::default()))),
            Ok(record(0, Settings::default()))
        );
        // Trailing bytes (a flash page) are ignored.
        let mut page = [0xFFu8; 256];
        page[..ENCODED_LEN].copy_from_slice(&bytes);
        assert_eq!(decode(&page), Ok(saved));
    }

    /// A format-4 record: `record`'s bytes (its servos not rated for speed) without the
    /// pivot's twelve, the version and payload length of format 4, checksummed again.
    fn format_4(record: &Record) -> Vec<u8> {
        assert!(
            !record.settings.servo_speed.rated(),
            "format 4 has no speed ratings"
        );
        let new = encode(record);
        let mut old = Vec::new();
        old.extend_from_slice(&new[..232]);
        old.extend_from_slice(&new[244..248]); // the sequence number
        old[4..8].copy_from_slice(&[4, 0, 224, 0]);
        let crc = crc32(&old);
        old.extend_from_slice(&crc.to_le_bytes());
        old
    }

    #[test]
    fn a_format_4_record_is_read_with_the_pivot_at_the_origin() {
        let mut s = Settings {
            speed_mm_s: 0.0,
            ..Settings::default()
        };
        s.servos.0[3].home_us = 1512.5;
        s.payload.com_mm = [1.0, 2.0, 3.0];
        s.payload.torque_kgcm = [0.0, 2.51, 600.0, 0.01, 12.0, 0.0];
        let mut with_pivot = s;
        with_pivot.pivot_mm = [0.0, 0.0, 300.0]; // not in a format-4 record: dropped
        let old = format_4(&Record {
            baud: 921_600,
            ..record(42, with_pivot)
        });
        assert_eq!(old.len(), 240);
        let expected = Record {
            sequence: 42,
            settings: s,
            baud: 921_600,
        };
        assert_eq!(expected.settings.pivot_mm, [0.0; 3]);
        assert_eq!(decode(&old), Ok(expected));
        let mut page = [0xFFu8; 256];
        page[..old.len()].copy_from_slice(&old);
        assert_eq!(decode(&page), Ok(expected));
        // Written again, it is format 5, with the same settings.
        assert_eq!(decode(&encode(&decode(&old).unwrap())), Ok(expected));
        // Its speed byte was reserved: anything but 0 there is refused.
        let mut bytes = old.clone();
        bytes[48 + 20 + 17] = 10;
        let crc = crc32(&bytes[..236]);
        bytes[236..240].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(decode(&bytes), Err(DecodeError::BadField { offset: 85 }));
        // Damage, cut short, are refused as in format 5.
        for cut in 0..old.len() {
            let mut partial = [0xFFu8; 256];
            partial[..cut].copy_from_slice(&old[..cut]);
            assert!(decode(&partial).is_err(), "cut at byte {cut}");
        }
        // A format-4 header on format-5 bytes is not taken for either.
        let mut mixed = default_bytes();
        mixed[4] = 4;
        assert_eq!(decode(&mixed), Err(DecodeError::BadLength(236)));
    }

    #[test]
    fn every_speed_rating_a_setting_takes_comes_back_from_flash() {
        use crate::settings::{ServoParam, ServoSel, SettingId};
        for c in 0..=255u8 {
            let text = if c == 0 {
                std::string::String::from("off")
            } else {
                std::format!("{}.{:02}", c / 100, c % 100)
            };
            let id = SettingId::Servo(ServoSel::One(2), ServoParam::SpeedS60Deg);
            let s = Settings::default().with(id, id.parse_value(&text).unwrap());
            let bytes = encode(&record(1, s));
            assert_eq!(bytes[48 + 20 + 17], c, "{text}");
            assert_eq!(decode(&bytes).unwrap().settings, s, "{text}");
        }
    }

    /// A format-3 record, as boards in the field hold: `record`'s bytes without the baud
    /// rate's four and the pivot's twelve, the version and payload length of format 3,
    /// checksummed again.
    fn format_3(record: &Record) -> Vec<u8> {
        let new = encode(record);
        let mut old = Vec::new();
        old.extend_from_slice(&new[..228]);
        old.extend_from_slice(&new[244..248]); // the sequence number
        old[4..8].copy_from_slice(&[3, 0, 220, 0]);
        let crc = crc32(&old);
        old.extend_from_slice(&crc.to_le_bytes());
        old
    }

    #[test]
    fn a_format_3_record_is_read_with_the_default_baud_rate() {
        let mut s = Settings {
            speed_mm_s: 0.0,
            ..Settings::default()
        };
        s.stream.text_bits = 10;
        s.servos.0[3].home_us = 1512.5;
        s.payload.com_mm = [1.0, 2.0, 3.0];
        let old = format_3(&Record {
            baud: 921_600, // not in a format-3 record: dropped by `format_3`
            ..record(41, s)
        });
        assert_eq!(old.len(), 236);
        let expected = Record {
            sequence: 41,
            settings: s,
            baud: 115_200,
        };
        assert_eq!(decode(&old), Ok(expected));
        // In a flash page, after erased bytes' worth of trailing data.
        let mut page = [0xFFu8; 256];
        page[..old.len()].copy_from_slice(&old);
        assert_eq!(decode(&page), Ok(expected));
        // Damage, cut short, are refused as in format 5.
        for cut in 0..old.len() {
            let mut partial = [0xFFu8; 256];
            partial[..cut].copy_from_slice(&old[..cut]);
            assert!(decode(&partial).is_err(), "cut at byte {cut}");
        }
        let mut flipped = old.clone();
        flipped[100] ^= 4;
        assert_eq!(decode(&flipped), Err(DecodeError::BadChecksum));
        // A format-3 header on format-5 bytes is not taken for either.
        let mut mixed = default_bytes();
        mixed[4] = 3;
        assert_eq!(decode(&mixed), Err(DecodeError::BadLength(236)));
    }

    #[test]
    fn a_baud_rate_that_uart0_does_not_take_is_refused() {
        for &baud in &BAUD_RATES {
            let r = Record {
                baud,
                ..record(3, Settings::default())
            };
            assert_eq!(decode(&encode(&r)), Ok(r));
        }
        for baud in [0, 9_599, 100_000, 1_000_000, u32::MAX] {
            let bytes = encode(&Record {
                baud,
                ..record(3, Settings::default())
            });
            assert_eq!(
                decode(&bytes),
                Err(DecodeError::BadField { offset: 228 }),
                "{baud}"
            );
        }
    }

    #[test]
    fn checksum_is_standard_crc32() {
        assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
        assert_eq!(crc32(b""), 0);
    }

    #[test]
    fn newer_follows_by_less_than_half_the_range() {
        assert!(is_newer(2, 1) && !is_newer(1, 2) && !is_newer(5, 5));
        assert!(
            is_newer(0, u32::MAX),
            "the wrap from u32::MAX to 0 is a step forward"
        );
        assert!(is_newer(3, u32::MAX - 3));
        assert!(!is_newer(u32::MAX, 0));
    }

    #[test]
    fn any_single_bit_flip_is_rejected() {
        let bytes = default_bytes();
        for i in 0..ENCODED_LEN {
            for bit in 0..8 {
                let mut damaged = bytes;
                damaged[i] ^= 1 << bit;
                assert!(decode(&damaged).is_err(), "byte {i} bit {bit}");
            }
        }
    }

    #[test]
    fn a_record_cut_short_is_rejected_wherever_the_write_stopped() {
        // Bytes from `cut` on still erased (0xFF), as a page program stopped there leaves them.
        let bytes = default_bytes();
        for cut in 0..ENCODED_LEN {
            let mut partial = [0xFFu8; ENCODED_LEN];
            partial[..cut].copy_from_slice(&bytes[..cut]);
            assert!(decode(&partial).is_err(), "cut at byte {cut}");
        }
    }

    #[test]
    fn foreign_and_short_data_are_rejected() {
        assert_eq!(decode(&[0xFF; ENCODED_LEN]), Err(DecodeError::BadMagic));
        assert_eq!(decode(&[0; 10]), Err(DecodeError::TooShort));
        let mut bytes = default_bytes();
        bytes[4] = 2;
        assert_eq!(decode(&bytes), Err(DecodeError::UnsupportedVersion(2)));
        let mut bytes = default_bytes();
        bytes[4] = 6;
        assert_eq!(decode(&bytes), Err(DecodeError::UnsupportedVersion(6)));
        // A format-3 record needs its 236 bytes, a format-4 one its 240, a format-5 one 252.
        assert_eq!(decode(&default_bytes()[..251]), Err(DecodeError::TooShort));
        assert_eq!(decode(&default_bytes()[..239]), Err(DecodeError::TooShort));
        assert_eq!(decode(&default_bytes()[..235]), Err(DecodeError::TooShort));
        let mut bytes = default_bytes();
        bytes[6] = 1;
        assert!(matches!(decode(&bytes), Err(DecodeError::BadLength(_))));
    }

    /// Re-seals damaged contents with a correct checksum, as a buggy writer would.
    fn reseal(mut bytes: [u8; ENCODED_LEN]) -> [u8; ENCODED_LEN] {
        let crc = crc32(&bytes[..CRC_OFFSET]);
        bytes[CRC_OFFSET..].copy_from_slice(&crc.to_le_bytes());
        bytes
    }

    #[test]
    fn intact_but_invalid_contents_are_rejected() {
        use crate::settings::SettingId;
        let default = default_bytes();
        let mut bytes = default;
        bytes[8..10].copy_from_slice(&10u16.to_le_bytes()); // frame_hz 10
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::OutOfRange {
                setting: SettingId::FrameHz,
                ..
            }))
        ));
        let mut bytes = default;
        bytes[12..16].copy_from_slice(&f32::NAN.to_le_bytes()); // speed NaN
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(_))
        ));
        let mut bytes = default;
        bytes[210] = 7; // reserved (bytes 10..12 were too, until the step guard took them)
        assert_eq!(
            decode(&reseal(bytes)),
            Err(DecodeError::BadField { offset: 210 })
        );
        let mut bytes = default;
        bytes[10..12].copy_from_slice(&1001u16.to_le_bytes()); // step guard 100.1 %
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::OutOfRange {
                setting: SettingId::StreamMaxStep,
                ..
            }))
        ));
        let mut bytes = default;
        bytes[10..12].copy_from_slice(&125u16.to_le_bytes()); // step guard 12.5 %
        let decoded = decode(&reseal(bytes)).expect("a guard in range");
        assert_eq!(decoded.settings.stream.max_step_pct, 12.5);
        let mut bytes = default;
        bytes[48 + 16] = 2; // servo 1 direction
        assert_eq!(
            decode(&reseal(bytes)),
            Err(DecodeError::BadField { offset: 64 })
        );
        let mut bytes = default;
        bytes[201] = 7; // stream.axis1
        assert_eq!(
            decode(&reseal(bytes)),
            Err(DecodeError::BadField { offset: 201 })
        );
        let mut bytes = default;
        bytes[208] = 2; // estop_action
        assert_eq!(
            decode(&reseal(bytes)),
            Err(DecodeError::BadField { offset: 208 })
        );
        let mut bytes = default;
        bytes[207] = 3; // estop_pin on a servo's GPIO
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(_))
        ));
        let mut bytes = default;
        bytes[202] = 0; // stream.axis2 = x, as axis1 is
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::StreamAxisTwice { .. }))
        ));
        let mut bytes = default;
        bytes[48 + 17] = 1; // servo 1's speed rating, 0.01 s: valid
        assert!(decode(&reseal(bytes)).is_ok());
        // In format 4 it was a reserved byte.
        let mut old = format_4(&record(7, Settings::default()));
        assert_eq!(old.len(), 240);
        old[48 + 17] = 1;
        let crc = crc32(&old[..236]);
        old[236..].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(decode(&old), Err(DecodeError::BadField { offset: 65 }));
        let mut bytes = default;
        bytes[48 + 18..48 + 20].copy_from_slice(&60_001u16.to_le_bytes()); // 600.01 kgf cm
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::OutOfRange { .. }))
        ));
        let mut bytes = default;
        bytes[212..216].copy_from_slice(&(-1.0f32).to_le_bytes()); // payload_g -1
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::OutOfRange {
                setting: SettingId::PayloadG,
                ..
            }))
        ));
        let mut bytes = default;
        bytes[240..244].copy_from_slice(&1000.5f32.to_le_bytes()); // pivot_z_mm 1000.5
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::OutOfRange {
                setting: SettingId::Pivot(2),
                ..
            }))
        ));
        let mut bytes = default;
        bytes[232..236].copy_from_slice(&f32::NAN.to_le_bytes()); // pivot_x_mm NaN
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(_))
        ));
        let mut bytes = default;
        bytes[24 + 20..24 + 24].copy_from_slice(&5.0f32.to_le_bytes()); // rod 5 mm
        assert!(matches!(
            decode(&reseal(bytes)),
            Err(DecodeError::Invalid(SettingError::BadGeometry(_)))
        ));
    }

    proptest::proptest! {
        #[test]
        fn decoding_arbitrary_bytes_never_panics(
            bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..300)
        ) {
            if let Ok(r) = decode(&bytes) {
                proptest::prop_assert!(r.settings.validate().is_ok());
            }
        }
    }
}
