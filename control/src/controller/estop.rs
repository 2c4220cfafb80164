//! Emergency stop ([`crate::safety`]): the board reports the input with
//! [`Controller::set_estop_input`]; while it is open or latched, moves and stream frames are
//! refused. [`Controller::servo_power`] says whether the servo-power output should be on.
//!
//! What it does when the input opens: the platform stops, or with `estop_action home` goes
//! home on its own (then the power goes off), the stream ends.

use kinematics_core::{Math, Pose};

use super::path::Purpose;
use super::Controller;
use crate::report::Notice;
use crate::safety::EstopAction;

impl<M: Math> Controller<M> {
    /// The e-stop input opened: stop (or go home), end the stream, power off.
    pub(super) fn on_estop(&mut self) {
        self.end_stream();
        self.motion.stop();
        self.returning_home = false;
        let safety = self.settings.safety;
        self.notify(Notice::EstopOpened {
            action: safety.estop_action,
            power_pin: safety.power_pin.is_some(),
        });
        match safety.estop_action {
            EstopAction::Freeze => self.servo_power = false,
            EstopAction::Home => {
                if *self.motion.pose() == Pose::HOME {
                    self.servo_power = false;
                } else if self.job.is_none() {
                    let limits = self.own_move_limits();
                    if let Err(e) = self.start_path(Pose::HOME, limits, Purpose::EstopHome) {
                        self.home_blocked(e);
                        self.servo_power = false;
                    }
                }
                // (With a command's job running, the way home starts when it ends: see
                // finish_path.)
            }
        }
    }

    /// The e-stop opened while a command's job ran (its motion refused): with `estop_action
    /// home`, the way home starts now (its check is the next job).
    pub(super) fn estop_home_after_job(&mut self) {
        if self.settings.safety.estop_action == EstopAction::Home && !self.motion.is_moving() {
            let limits = self.own_move_limits();
            if let Err(e) = self.start_path(Pose::HOME, limits, Purpose::EstopHome) {
                self.home_blocked(e);
                self.servo_power = false;
            }
        }
    }
}
