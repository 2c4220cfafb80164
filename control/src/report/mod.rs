//! Everything the user reads, worded in one place: final replies, error codes and messages,
//! data lines, notices, help, the banner and the echo. Nothing below the controller imports
//! it; host programs print the board's own words through it ([`refusal`], [`write_error`]).
//!
//! - [`errors`](self::Code): the error vocabulary, the code and message of every refusal;
//! - `format`: how numbers, poses and setting values are written;
//! - `near`: the known name closest to a mistyped command or setting ("did you mean");
//! - `replies`: the writers of every reply, data line and notice.
//!
//! # Output conventions
//!
//! - Every output line ends with CR LF.
//! - Every completed, non-empty input line gets exactly one **final reply**, always the last
//!   line written for it:
//!   - `ok` - done (any data came before it, on `# ` lines);
//!   - `error:<code> <message>` - refused; nothing happened. `<code>` is one of the
//!     [`Code`]s (lowercase words joined by `-`); the message names the field, leg, servo or
//!     limit involved.
//! - Every other line starts with `# `: data (`# key: value`), help text, the banner and
//!   notices about things that happened on their own (`# fault: ...`, `# link lost: ...`,
//!   `# warning: ...`, e.g. about the settings found in flash at power-up).
//!   A program can therefore read lines until one starts with `ok` or `error:`, and ignore
//!   or parse the `# ` lines before it.
//! - A blank line gets no reply (with echo on, just a fresh prompt).
//! - With echo on (the default, for terminals) typed characters are echoed, the line end is
//!   echoed as CR LF and a prompt `> ` follows every reply. `set echo off` turns off echo and
//!   prompt on that link, for programs.
//!
//! Numbers: poses in mm and degrees with 3 decimals, arm angles in degrees with 3 decimals,
//! pulse widths in microseconds with 2 decimals.

mod errors;
mod format;
mod near;
mod replies;

pub use errors::{usage, write_error_codes_doc, Code};
pub use format::{degrees, Fixed, PoseText, Six, ValueText, Vector};
pub use near::{nearest_setting, nearest_verb};
pub use replies::{
    board_id_digits, kinematics_refusal, refusal, write_banner, write_echo, write_echo_chars,
    write_error, write_held_echo, write_notice, write_ok, write_prompt, Fault, Listing,
    MotionReport, Notice, Saved, StatusReport, StreamCounts, EOL, HELP, PROMPT, USB_MANUFACTURER,
    USB_PID, USB_PRODUCT, USB_VID, VERSION,
};

#[cfg(test)]
mod tests {
    use kinematics_core::geometry::GeometryError;
    use kinematics_core::ik::IkError;
    use kinematics_core::pose::Axis;
    use kinematics_core::servo::{ServoError, ServoField};

    use kinematics_core::KinematicsError;

    use super::*;
    use crate::command::{Field, Missing, ParseError, Verb};
    use crate::error::{Error, PoseError};
    use crate::payload::TorqueError;
    use crate::protocol::{Lost, Spoiled};
    use crate::safety::Estop;
    use crate::settings::{
        Expected, LayoutParam, ServoParam, ServoSel, SettingError, SettingId, BAUD_RATES,
    };
    use crate::word::word;

    /// One error of every kind.
    pub(crate) fn one_of_each() -> std::vec::Vec<Error> {
        let setting = SettingId::FrameHz;
        std::vec![
            Error::Spoiled(Spoiled::TooLong),
            Error::Spoiled(Spoiled::RxOverflow(Lost {
                bytes: 3,
                in_uart: false,
            })),
            Error::Spoiled(Spoiled::BadByte(0xC2)),
            Error::Parse(ParseError::UnknownCommand { word: word("fly") }),
            Error::Parse(ParseError::MissingField {
                what: Missing::Axis(Axis::Yaw),
                verb: Verb::Pose,
            }),
            Error::Parse(ParseError::ExtraField {
                word: word("7"),
                verb: Verb::Home,
            }),
            Error::Parse(ParseError::BadNumber {
                field: Field::Axis(Axis::X),
                word: word("abc"),
            }),
            Error::Parse(ParseError::NotFinite {
                field: Field::Axis(Axis::Roll),
                word: word("nan"),
            }),
            Error::Parse(ParseError::NumberTooLarge {
                field: Field::PulseUs,
                word: word("1e39"),
            }),
            Error::Parse(ParseError::BadServo { word: word("7") }),
            Error::Parse(ParseError::UnknownAxis { word: word("w") }),
            Error::Parse(ParseError::DuplicateAxis { axis: Axis::Z }),
            Error::Parse(ParseError::BadAssignment { word: word("z") }),
            Error::Parse(ParseError::UnknownSetting {
                word: word("colour")
            }),
            Error::Setting(SettingError::BadValue {
                setting: SettingId::Echo,
                word: word("maybe"),
                expected: Expected::OnOrOff,
            }),
            Error::Setting(SettingError::NotOneOf {
                setting: SettingId::Baud,
                word: word("100000"),
                allowed: &BAUD_RATES,
            }),
            Error::Setting(SettingError::OutOfRange {
                setting,
                value: 20.0,
                min: 50.0,
                max: 333.0,
                unit: "Hz",
                off_allowed: false,
            }),
            Error::Setting(SettingError::BadServoConfig(ServoError::PulseOutOfRange {
                servo: 2,
                field: ServoField::Max,
                value_us: 3000.0,
            })),
            Error::Setting(SettingError::BadGeometry(GeometryError::NoHomeHeight {
                leg: 1
            })),
            Error::Pose(IkError::Unreachable { leg: 3 }),
            Error::Pose(IkError::ServoLimit {
                servo: 2,
                pulse_us: 1950.0,
                min_us: 1100.0,
                max_us: 1900.0,
            }),
            Error::Pose(IkError::AngleTooLarge {
                axis: Axis::Pitch,
                value_rad: 4.0,
            }),
            Error::Pose(IkError::NonFinite { axis: Axis::Y }),
            Error::PathBlocked {
                percent: 42.0,
                cause: PoseError::Ik(IkError::Unreachable { leg: 5 }),
            },
            Error::PathBlocked {
                percent: 7.5,
                cause: PoseError::Torque(TorqueError::Over {
                    servo: 3,
                    needed_kgcm: -4.25,
                    rated_kgcm: 4.0,
                }),
            },
            Error::PoseConflict {
                cause: PoseError::Ik(IkError::ServoLimit {
                    servo: 1,
                    pulse_us: 1000.0,
                    min_us: 1100.0,
                    max_us: 1900.0,
                }),
            },
            Error::PoseConflict {
                cause: PoseError::Torque(TorqueError::Unknown(KinematicsError::DeadCentre {
                    leg: 2
                })),
            },
            Error::Torque(TorqueError::Over {
                servo: 6,
                needed_kgcm: 12.5,
                rated_kgcm: 10.0,
            }),
            Error::PulseOutsideLimits {
                servo: 2,
                pulse_us: 2000.0,
                min_us: 1100.0,
                max_us: 1900.0,
            },
            Error::NoPose(KinematicsError::NotConverged {
                iterations: 8,
                residual: 0.5,
            }),
            Error::NoPose(KinematicsError::ElbowFlipped { leg: 4 }),
            Error::Busy,
            Error::Pending,
            Error::Setting(SettingError::StreamAxisTwice {
                axis: Axis::Roll,
                first: 1,
                second: 4,
            }),
            Error::Setting(SettingError::PinTwice { pin: 15 }),
            Error::Estop(Estop::Open),
            Error::Estop(Estop::Latched),
            Error::SaveFailed(crate::store::SaveError::Verify {
                offset: 4101,
                wrote: 0,
                read: 1,
            }),
        ]
    }

    #[test]
    fn every_error_code_is_distinct_and_every_code_is_used() {
        let codes: std::vec::Vec<&str> = Code::ALL.iter().map(|c| c.as_str()).collect();
        let mut sorted = codes.clone();
        sorted.sort_unstable();
        sorted.dedup();
        assert_eq!(sorted.len(), codes.len(), "duplicate code in {codes:?}");
        let used: std::vec::Vec<Code> = one_of_each().iter().map(Error::code).collect();
        for code in Code::ALL {
            assert!(used.contains(&code), "no example error for {code}");
        }
        for code in codes {
            assert!(
                code.bytes().all(|b| b.is_ascii_lowercase() || b == b'-'),
                "{code}"
            );
        }
    }

    #[test]
    fn error_replies_are_one_line_with_code_and_message() {
        for e in one_of_each() {
            let mut s = std::string::String::new();
            write_error(&mut s, &e);
            let expected_start = std::format!("error:{} ", e.code());
            assert!(s.starts_with(&expected_start), "{s}");
            assert!(s.ends_with("\r\n") && s.matches('\n').count() == 1, "{s:?}");
            assert!(
                s.len() > expected_start.len() + 10,
                "message too short: {s}"
            );
            assert!(s.is_ascii(), "{s}");
            assert_eq!(s, std::format!("{}\r\n", refusal(&e)));
        }
    }

    #[test]
    fn a_kinematics_refusal_is_the_board_s_for_the_ik_and_names_the_leg_or_the_cause() {
        // The IK's refusal reads as the board's reply, code and all.
        let ik = IkError::Unreachable { leg: 2 };
        assert_eq!(
            std::format!("{}", kinematics_refusal(&KinematicsError::Ik(ik))),
            std::format!("{}", refusal(&Error::from(ik)))
        );
        let words = |e: KinematicsError| std::format!("{}", kinematics_refusal(&e));
        assert!(words(KinematicsError::DeadCentre { leg: 5 }).starts_with("leg 5's arm"));
        assert!(words(KinematicsError::Singular { pivot_ratio: 0.0 }).contains("singular pose"));
        assert!(words(KinematicsError::GimbalLock { pitch_rad: 1.5 }).contains("+-90"));
        // One line each, never empty.
        for e in [
            KinematicsError::ZeroLength { leg: 1 },
            KinematicsError::NotConverged {
                iterations: 3,
                residual: 0.5,
            },
            KinematicsError::DeadCentre { leg: 5 },
        ] {
            let w = words(e);
            assert!(!w.is_empty() && !w.contains('\n'), "{w:?}");
        }
    }

    #[test]
    fn the_same_refusal_reads_the_same_whichever_layer_it_comes_from() {
        // A setting value refused while parsing and one refused by validation.
        let parsed = Error::from(ParseError::Setting(SettingError::NotOneOf {
            setting: SettingId::Baud,
            word: word("7"),
            allowed: &BAUD_RATES,
        }));
        let direct = Error::from(SettingError::NotOneOf {
            setting: SettingId::Baud,
            word: word("7"),
            allowed: &BAUD_RATES,
        });
        assert_eq!(parsed, direct);
        let text = std::format!("{}", refusal(&direct));
        assert_eq!(
            text,
            "error:bad-value baud: '7' is not one of 9600 19200 38400 57600 115200 230400 460800 921600"
        );
        assert_eq!(
            Error::from(ParseError::Spoiled(Spoiled::TooLong)),
            Error::Spoiled(Spoiled::TooLong)
        );
    }

    #[test]
    fn messages_name_what_is_wrong() {
        let text = |e: Error| std::format!("{e}");
        assert!(text(Error::Pose(IkError::Unreachable { leg: 3 })).contains("leg 3"));
        let limit = text(Error::Pose(IkError::ServoLimit {
            servo: 2,
            pulse_us: 1950.123,
            min_us: 1100.0,
            max_us: 1900.0,
        }));
        assert!(
            limit.contains("servo 2") && limit.contains("1950.12") && limit.contains("1900.00")
        );
        let field = text(Error::Setting(SettingError::NotFinite {
            setting: SettingId::Servo(ServoSel::One(4), ServoParam::TrimUs),
            word: word("inf"),
        }));
        assert!(
            field.contains("servo4.trim_us") && field.contains("'inf'"),
            "{field}"
        );
        let layout = text(Error::Setting(SettingError::BadNumber {
            setting: SettingId::Layout(LayoutParam::RodMm),
            word: word("x"),
        }));
        assert!(layout.starts_with("rod_mm:"), "{layout}");
        let missing = text(Error::Parse(ParseError::MissingField {
            what: Missing::Axis(Axis::Pitch),
            verb: Verb::Pose,
        }));
        assert_eq!(
            missing,
            "missing pitch; usage: pose <x> <y> <z> <roll> <pitch> <yaw>"
        );
        assert_eq!(
            text(Error::Setting(SettingError::OutOfRange {
                setting: SettingId::SpeedMmS,
                value: 5000.0,
                min: 0.1,
                max: 1000.0,
                unit: "mm/s",
                off_allowed: true,
            })),
            "speed_mm_s 5000 is outside 0.1..1000 mm/s (or 0/off)"
        );
        // A close name is suggested; none when nothing is close.
        assert_eq!(
            text(Error::Parse(ParseError::UnknownCommand {
                word: word("stauts")
            })),
            "'stauts' is not a command; did you mean status? type help"
        );
        assert_eq!(
            text(Error::Parse(ParseError::UnknownSetting {
                word: word("rdo_mm")
            })),
            "'rdo_mm' is not a setting; did you mean rod_mm? type config for the list"
        );
        assert_eq!(
            text(Error::Parse(ParseError::UnknownSetting {
                word: word("colour")
            })),
            "'colour' is not a setting; type config for the list"
        );
        // Every word the setting takes, the two config shows first.
        assert_eq!(
            text(Error::Setting(SettingError::BadValue {
                setting: SettingId::Echo,
                word: word("maybe"),
                expected: Expected::OnOrOff,
            })),
            "echo: 'maybe' is not on or off (1 / 0)"
        );
        assert_eq!(
            text(Error::Setting(SettingError::BadValue {
                setting: SettingId::Servo(ServoSel::All, ServoParam::Dir),
                word: word("0"),
                expected: Expected::NormalOrReversed,
            })),
            "servos.dir: '0' is not normal or reversed (1 / +1 / -1)"
        );
        assert_eq!(
            text(Error::Setting(SettingError::OutOfRange {
                setting: SettingId::FrameHz,
                value: -50.0,
                min: 50.0,
                max: 333.0,
                unit: "Hz",
                off_allowed: false,
            })),
            "frame_hz -50 is outside 50..333 Hz"
        );
        assert_eq!(
            text(Error::Parse(ParseError::NoCommand)),
            "only separators, no command; type help"
        );
        assert_eq!(
            text(Error::Torque(TorqueError::Over {
                servo: 3,
                needed_kgcm: -4.2512,
                rated_kgcm: 4.0,
            })),
            "servo 3 would need 4.251 kgf cm to hold the payload, over its rating 4.00 kgf cm"
        );
        assert_eq!(
            text(Error::PulseOutsideLimits {
                servo: 2,
                pulse_us: 2000.0,
                min_us: 1100.0,
                max_us: 1900.0,
            }),
            "servo 2: 2000.00 us is outside its limits 1100.00..1900.00 us (servo2.min_us, max_us)"
        );
        // The pulse as typed, not rounded onto the limit it exceeds.
        assert_eq!(
            text(Error::PulseOutsideLimits {
                servo: 2,
                pulse_us: 1900.004,
                min_us: 1100.0,
                max_us: 1900.0,
            }),
            "servo 2: 1900.004 us is outside its limits 1100.00..1900.00 us (servo2.min_us, max_us)"
        );
        assert!(
            text(Error::NoPose(KinematicsError::ElbowFlipped { leg: 4 }))
                .contains("(leg 4's arm would have to fold through its rod)")
        );
        assert_eq!(
            text(Error::Parse(ParseError::BadServo { word: word("7") })),
            "'7' is not a servo number; servos are 1 to 6"
        );
    }

    /// The banner names the board by its id when the board has one (README.md, "Try it"):
    /// 16 hexadecimal digits, most significant first, as the USB serial number.
    #[test]
    fn banner_with_and_without_a_board_id() {
        let mut out = std::string::String::new();
        write_banner(&mut out, Some(0xE660_C0D1_C7AB_2F28));
        assert_eq!(
            out,
            std::format!(
                "# hexapod control {VERSION} on board E660C0D1C7AB2F28: poses in mm and degrees; \
                 type help\r\n"
            )
        );
        out.clear();
        write_banner(&mut out, None);
        assert_eq!(
            out,
            std::format!("# hexapod control {VERSION}: poses in mm and degrees; type help\r\n")
        );
        assert_eq!(&board_id_digits(0x0123_4567_89AB_CDEF), b"0123456789ABCDEF");
        assert_eq!(&board_id_digits(0xF), b"000000000000000F");
    }
}
