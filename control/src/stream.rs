//! Pose frames streamed by motion-simulator software (FlyPT Mover, SimTools, SimHub), on the
//! same link as the command lines: their grammar, recognised byte by byte.
//!
//! - **Binary frame** (16 bytes): `A5 5A`, six 16-bit big-endian counts for x, y, z, roll,
//!   pitch, yaw, then `0D 0A`. FlyPT Mover writes it with the output string
//!   `<165><90><Axis1a><Axis2a><Axis3a><Axis4a><Axis5a><Axis6a><13><10>` (16-bit binary).
//!   It starts with a byte no command line can contain (`A5` is not ASCII), so it may come at
//!   any line start. The header and the trailer are 14 bytes apart: a frame whose trailer is
//!   not where it should be (a lost or extra byte) is damaged, and decoding resynchronises on
//!   the next `A5 5A` among the bytes already received, so one lost byte costs one frame.
//! - **Text frame** (the SimTools / Mini-6DOF profiles' format): six decimal counts separated
//!   by commas and ended by `X`, e.g. `127,127,131,127,120,127X`, with no line end. It starts
//!   with a digit, which no command does. How a stream picks up again after line noise (an `X`
//!   ends whatever a digit began; a frame counts only if nothing else came since the last
//!   frame's `X` or line end) is the line assembler's: see [`crate::protocol`].
//!
//! What the counts mean is [`StreamSettings`]' (the `stream.*` settings): count `c` of a
//! `b`-bit axis is the fraction `(c - 2^(b-1)) / 2^(b-1)` of that axis' full scale (mm for x,
//! y, z; degrees for roll, pitch, yaw; a negative full scale inverts the axis), so the middle
//! count is the home pose. Binary frames are 16-bit in the order x y z roll pitch yaw; text
//! frames have the settable bit depth and axis order of an existing profile.
//!
//! What no format can catch, a digit lost from a text frame's count (`127` read as `12`),
//! makes a wrong but well-formed frame. The optional step guard (`stream.max_step_pct`, off by
//! default) catches most of them: a frame that moves any axis by more than that share of its
//! full scale from the last frame taken is dropped, unless the frame before it (dropped too)
//! already said nearly the same: so one wrong frame is never applied and a real jump costs
//! one frame ([`StreamSettings::step_allowed`]).

use kinematics_core::pose::Axis;
use kinematics_core::Pose;

/// Bytes in a binary frame.
pub const BINARY_FRAME_LEN: usize = 16;
/// The binary frame's first byte (not ASCII: no command line contains it).
pub const BINARY_HEADER: [u8; 2] = [0xA5, 0x5A];
/// The binary frame's last two bytes.
pub const BINARY_TRAILER: [u8; 2] = [0x0D, 0x0A];
/// Ends a text frame.
pub const TEXT_FRAME_END: u8 = b'X';
/// Counts in a frame.
pub const COUNTS: usize = 6;

/// The six counts of a frame, in the order they came.
pub type Counts = [u32; COUNTS];

/// A stream frame's counts, by the format it came in (their meaning differs: see the
/// settings).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Frame {
    /// A binary frame: 16-bit counts, axes in the order x y z roll pitch yaw.
    Binary(Counts),
    /// A text frame: counts of the configured bit depth, axes in the configured order.
    Text(Counts),
}

/// Bits of a binary frame's counts.
pub const BINARY_BITS: u8 = 16;
/// Fewest bits a text frame's counts may have (`stream.bits`).
pub const TEXT_BITS_MIN: u8 = 8;
/// Most bits a text frame's counts may have (`stream.bits`).
pub const TEXT_BITS_MAX: u8 = 16;

/// How stream counts become a pose (the `stream.*` settings).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StreamSettings {
    /// Full scale of each axis, [`Axis::ALL`] order: mm for x, y, z, degrees for roll,
    /// pitch, yaw (`stream.x_mm` .. `stream.yaw_deg`). The extreme counts mean about plus and
    /// minus this; negative inverts the axis; 0 keeps the axis at 0.
    pub full_scale: [f32; 6],
    /// Bits of a text frame's counts (`stream.bits`).
    pub text_bits: u8,
    /// The axis each of a text frame's six counts drives (`stream.axis1` .. `stream.axis6`);
    /// `None`: that count is ignored. No axis twice.
    pub text_order: [Option<Axis>; 6],
    /// The step guard (`stream.max_step_pct`): the largest change of an axis between two
    /// frames, percent of its full scale (a whole number of tenths); 0 = off.
    pub max_step_pct: f32,
}

impl Default for StreamSettings {
    fn default() -> StreamSettings {
        StreamSettings {
            full_scale: [25.0, 25.0, 15.0, 15.0, 15.0, 20.0],
            text_bits: 8,
            text_order: Axis::ALL.map(Some),
            max_step_pct: 0.0,
        }
    }
}

/// Why a whole frame's counts are not a pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CountError {
    /// A text frame's count does not fit its bit depth (`stream.bits`).
    TooLarge {
        /// Which count (1..=6).
        count: u8,
    },
}

impl StreamSettings {
    /// The pose a frame's counts mean (see the module documentation).
    pub fn to_pose(&self, frame: Frame) -> Result<Pose, CountError> {
        Ok(self.pose_of(&self.fractions(frame)?))
    }

    /// The pose of each axis' share of its full scale ([`StreamSettings::fractions`]).
    pub fn pose_of(&self, fractions: &[f32; 6]) -> Pose {
        let mut values = [0.0f32; 6];
        for (v, (f, scale)) in values.iter_mut().zip(fractions.iter().zip(self.full_scale)) {
            *v = f * scale;
        }
        let [x, y, z, roll, pitch, yaw] = values;
        Pose::from_degrees(x, y, z, roll, pitch, yaw)
    }

    /// Each axis' share of its full scale a frame's counts mean, -1..1, [`Axis::ALL`] order
    /// (0 for an axis no count drives).
    pub fn fractions(&self, frame: Frame) -> Result<[f32; 6], CountError> {
        let (counts, bits, order) = match frame {
            Frame::Binary(counts) => (counts, BINARY_BITS, Axis::ALL.map(Some)),
            Frame::Text(counts) => (counts, self.text_bits, self.text_order),
        };
        let half = 1u32 << (bits - 1);
        let mut values = [0.0f32; 6];
        for (i, (&count, axis)) in counts.iter().zip(order).enumerate() {
            if count >= 2 * half {
                return Err(CountError::TooLarge { count: i as u8 + 1 });
            }
            if let Some(axis) = axis {
                values[axis as usize] = centred_share(count as i32 - half as i32, bits - 1);
            }
        }
        Ok(values)
    }

    /// A step guard kept to tenths of a percent (what the flash record holds): `value`
    /// (0..=100) rounded to the nearest tenth.
    pub fn quantise_step_pct(value: f32) -> f32 {
        f32::from(step_tenths(value)) / 10.0
    }

    /// Whether the step guard lets a frame ([`StreamSettings::fractions`]) follow `taken`, the
    /// last frame taken, or `seen`, the frame just before it (dropped by the guard, or
    /// `taken`): no axis moved by more than `max_step_pct` of its full scale from either
    /// (always, with the guard off). So a lone wrong frame is dropped and the next good one,
    /// near `taken`, applied; a real jump is taken at its second frame, near the first.
    pub fn step_allowed(&self, taken: &[f32; 6], seen: &[f32; 6], frame: &[f32; 6]) -> bool {
        if self.max_step_pct <= 0.0 {
            return true;
        }
        // Counts are whole: a step exactly at the limit is within it (f32 rounding aside).
        let limit = self.max_step_pct / 100.0 * (1.0 + 1e-4);
        let near = |from: &[f32; 6]| {
            (0..COUNTS).all(|a| self.full_scale[a] == 0.0 || (frame[a] - from[a]).abs() <= limit)
        };
        near(taken) || near(seen)
    }
}

/// `offset / 2^shift` (`|offset| <= 2^shift`, `shift` at most 15), exactly: the one conversion
/// to `f32` (exact below 2^24) and the division by a power of two as an exponent lowered in
/// integer instructions (the compiler's conversions, subtraction and division cost a frame's
/// six axes about 2,000 cycles on the RP2040).
fn centred_share(offset: i32, shift: u8) -> f32 {
    if offset == 0 {
        return 0.0;
    }
    // |offset| >= 1: the quotient is at least 2^-15, a normal number.
    f32::from_bits((offset as f32).to_bits() - (u32::from(shift) << 23))
}

/// A step guard (percent, 0..=100) in tenths of a percent, rounded to the nearest (what the
/// flash record keeps; `as` saturates and takes NaN to 0).
pub fn step_tenths(value: f32) -> u16 {
    (value * 10.0 + 0.5) as u16
}

/// What a byte did to a binary frame in progress.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinaryFeed {
    /// More bytes needed.
    Pending,
    /// A whole frame: its counts.
    Frame(Counts),
    /// The bytes so far are not a frame (counted as one damaged frame). Decoding goes on with
    /// the bytes it kept (a later `A5 5A`), if any: see [`BinaryFrame::is_empty`].
    Damaged,
    /// The frame's first byte (`A5`) was not followed by `5A`: it was a stray byte, not the
    /// start of a frame; this byte was not taken (the caller treats both as other input).
    NotAFrame,
}

/// A binary frame being received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BinaryFrame {
    bytes: [u8; BINARY_FRAME_LEN],
    len: usize,
}

impl Default for BinaryFrame {
    fn default() -> Self {
        Self::new()
    }
}

impl BinaryFrame {
    /// Nothing received.
    pub const fn new() -> Self {
        BinaryFrame {
            bytes: [0; BINARY_FRAME_LEN],
            len: 0,
        }
    }

    /// True when no frame is in progress (the next byte belongs to the lines).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Bytes of the frame in progress received so far.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Feeds one byte. The first byte of a frame must be `A5` (the caller routes it here).
    pub fn feed(&mut self, byte: u8) -> BinaryFeed {
        if self.len == 1 && byte != BINARY_HEADER[1] {
            self.len = 0;
            return BinaryFeed::NotAFrame;
        }
        self.bytes[self.len] = byte;
        self.len += 1;
        if self.len <= BINARY_HEADER.len() {
            return BinaryFeed::Pending;
        }
        if self.len < BINARY_FRAME_LEN {
            return BinaryFeed::Pending;
        }
        if self.bytes[BINARY_FRAME_LEN - 2..] != BINARY_TRAILER {
            self.resync();
            return BinaryFeed::Damaged;
        }
        let counts = core::array::from_fn(|i| {
            u32::from(u16::from_be_bytes([
                self.bytes[2 + 2 * i],
                self.bytes[3 + 2 * i],
            ]))
        });
        self.len = 0;
        BinaryFeed::Frame(counts)
    }

    /// After a damaged frame: keeps the bytes from the next `A5 5A` (or a last lone `A5`) on,
    /// if any, as the start of the next frame.
    fn resync(&mut self) {
        let kept = (1..self.len)
            .find(|&start| matches!(&self.bytes[start..self.len], [0xA5] | [0xA5, 0x5A, ..]));
        match kept {
            Some(start) => {
                self.bytes.copy_within(start..self.len, 0);
                self.len -= start;
            }
            None => self.len = 0,
        }
    }
}

/// Whether a (command) line that has just started with `byte` is a text frame's beginning.
pub fn starts_text_frame(byte: u8) -> bool {
    byte.is_ascii_digit()
}

/// The counts of a text frame (its text without the final `X`): exactly six decimal counts
/// separated by commas, each below 2^16; `None` if it is not one (a damaged frame).
pub fn parse_text_frame(text: &str) -> Option<Counts> {
    let mut counts = [0u32; COUNTS];
    let mut fields = text.split(',');
    for count in counts.iter_mut() {
        let field = fields.next()?;
        if field.is_empty() || field.len() > 5 || !field.bytes().all(|b| b.is_ascii_digit()) {
            return None;
        }
        let mut value = 0u32;
        for b in field.bytes() {
            value = value * 10 + u32::from(b - b'0');
        }
        if value > u32::from(u16::MAX) {
            return None;
        }
        *count = value;
    }
    fields.next().is_none().then_some(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn centred_shares_are_the_exact_quotients() {
        for bits in TEXT_BITS_MIN..=BINARY_BITS {
            let half = 1i32 << (bits - 1);
            for count in 0..2 * half {
                let exact = (count as f64 - half as f64) / half as f64;
                let share = centred_share(count - half, bits - 1);
                assert_eq!(f64::from(share), exact, "{bits} bits, count {count}");
                assert_eq!(share.to_bits(), (exact as f32).to_bits());
            }
        }
    }

    fn frame(counts: [u16; 6]) -> std::vec::Vec<u8> {
        let mut bytes = std::vec![0xA5, 0x5A];
        for c in counts {
            bytes.extend_from_slice(&c.to_be_bytes());
        }
        bytes.extend_from_slice(&[0x0D, 0x0A]);
        bytes
    }

    /// Feeds a byte stream (each frame starting where the decoder is empty and the byte is
    /// A5, as the line assembler routes it); returns frames and damaged counts.
    fn decode(bytes: &[u8]) -> (std::vec::Vec<Counts>, usize, usize) {
        let mut d = BinaryFrame::new();
        let (mut frames, mut damaged, mut other) = (std::vec::Vec::new(), 0, 0);
        for &b in bytes {
            if d.is_empty() && b != 0xA5 {
                other += 1;
                continue;
            }
            match d.feed(b) {
                BinaryFeed::Pending => {}
                BinaryFeed::Frame(c) => frames.push(c),
                BinaryFeed::Damaged => damaged += 1,
                BinaryFeed::NotAFrame => {
                    damaged += 1;
                    other += 1;
                }
            }
        }
        (frames, damaged, other)
    }

    #[test]
    fn a_binary_frame_gives_its_six_counts() {
        let (frames, damaged, _) = decode(&frame([0, 1, 0x8000, 0xFFFF, 0x0D0A, 0xA55A]));
        assert_eq!(frames, [[0, 1, 0x8000, 0xFFFF, 0x0D0A, 0xA55A]]);
        assert_eq!(damaged, 0);
    }

    #[test]
    fn a_lost_byte_costs_one_frame_and_decoding_resynchronises() {
        let mut bytes = std::vec::Vec::new();
        let counts: std::vec::Vec<[u16; 6]> = (0..5)
            .map(|i| [i, i + 1, i + 2, i + 3, i + 4, i + 5])
            .collect();
        for c in &counts {
            bytes.extend(frame(*c));
        }
        // Lose one byte from the second frame's counts: it is damaged, the others arrive.
        bytes.remove(16 + 5);
        let (frames, damaged, _) = decode(&bytes);
        assert_eq!(damaged, 1);
        let want: std::vec::Vec<Counts> = [0, 2, 3, 4]
            .iter()
            .map(|&k| counts[k].map(u32::from))
            .collect();
        assert_eq!(frames, want);
    }

    #[test]
    fn an_extra_byte_and_garbage_are_skipped() {
        let mut bytes = frame([1; 6]);
        bytes.insert(7, 0x00); // an extra byte inside the first frame
        bytes.extend_from_slice(&[0xA5, 0x00, 0xA5, 0xA5, 0x13]); // garbage
        bytes.extend(frame([2; 6]));
        let (frames, damaged, _) = decode(&bytes);
        assert_eq!(frames, [[2; 6]]);
        assert!(damaged >= 2, "{damaged}");
    }

    #[test]
    fn header_bytes_inside_the_counts_do_not_confuse_it() {
        // A5 5A and 0D 0A inside the counts are data.
        let c = [0xA55A, 0x0D0A, 0xA55A, 0x0D0A, 0x5AA5, 0x0AA5];
        let mut bytes = frame(c);
        bytes.extend(frame(c));
        let (frames, damaged, _) = decode(&bytes);
        assert_eq!(frames, [c.map(u32::from), c.map(u32::from)]);
        assert_eq!(damaged, 0);
    }

    #[test]
    fn text_frames_are_six_counts() {
        assert_eq!(
            parse_text_frame("127,0,255,65535,00012,3"),
            Some([127, 0, 255, 65535, 12, 3])
        );
        for bad in [
            "",
            "1,2,3,4,5",
            "1,2,3,4,5,6,7",
            "1,,3,4,5,6",
            "1,2,3,4,5,65536",
            "1,2,3,4,5,6 ",
            "1,2,3,4,5,-6",
            "1,2,3,4,5,6X",
            "123456,1,1,1,1,1",
        ] {
            assert_eq!(parse_text_frame(bad), None, "{bad:?}");
        }
        assert!(starts_text_frame(b'0') && starts_text_frame(b'9'));
        assert!(!starts_text_frame(b'p') && !starts_text_frame(b'?') && !starts_text_frame(b'-'));
    }

    proptest::proptest! {
        #[test]
        fn decoding_any_bytes_never_panics_and_frames_have_their_shape(
            bytes in proptest::collection::vec(proptest::num::u8::ANY, 0..400)
        ) {
            let _ = decode(&bytes);
            let text = std::string::String::from_utf8_lossy(&bytes);
            if let Some(c) = parse_text_frame(&text) {
                proptest::prop_assert!(c.iter().all(|&v| v <= 0xFFFF));
            }
        }
    }
}
