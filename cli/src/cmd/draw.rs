//! `hexapod draw`: the platform at a pose (`crate::draw`), as SVG and PNG; a pose it cannot take
//! is drawn all the same, with the board's words for why.

use std::path::PathBuf;

use clap::Args;
use control::command::{self, Command};
use control::settings::Settings;
use kinematics_core::Pose;

use super::{wrote_pictures, Formats};
use crate::build_file;
use crate::draw::{self, Verdict};
use crate::error::{board_words, Error};
use crate::picture::write_scene;

// The options (the subcommand's help is its line in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// The platform (a build file); the default platform without it
    #[arg(long)]
    settings: Option<PathBuf>,
    /// The pose: x y z roll pitch yaw (mm, degrees), as `pose` takes it
    #[arg(long, default_value = "0 0 0 0 0 0", allow_hyphen_values = true)]
    pose: String,
    /// Where to write: FILE.svg and FILE.png
    #[arg(short, long, default_value = "platform")]
    output: PathBuf,
    #[command(flatten)]
    formats: Formats,
}

impl Cmd {
    /// Draws the platform; the files written, and why the pose is refused if it is.
    pub fn run(self) -> Result<String, Error> {
        let settings = match &self.settings {
            Some(path) => build_file::read(path)?.settings,
            None => Settings::default(),
        };
        let pose = parse_pose(&self.pose)?;
        let shown: Vec<String> = self.pose.split_whitespace().map(str::to_string).collect();
        let model = draw::model(&settings, &pose).map_err(|why| Error::Pose {
            pose: self.pose.clone(),
            why,
        })?;
        let written = write_scene(
            &draw::scene(&model, &shown.join(" ")),
            &self.output,
            self.formats.svg(),
            self.formats.png(),
        )?;
        let mut summary = wrote_pictures(&written);
        if let Verdict::Refused { words, .. } = &model.verdict {
            summary = refused(&summary, words);
        }
        Ok(summary)
    }
}

/// A pose typed as the firmware's `pose` command takes it (`x y z roll pitch yaw`, mm and
/// degrees), read by the firmware's own parser; the board's words if it is not one.
fn parse_pose(text: &str) -> Result<Pose, Error> {
    let line = format!("pose {text}");
    match command::parse(&line.to_ascii_lowercase()) {
        Ok(Command::Pose(pose)) => Ok(pose),
        Ok(_) => Err(Error::Pose {
            pose: text.to_string(),
            why: NOT_A_POSE.to_string(),
        }),
        Err(e) => Err(Error::Pose {
            pose: text.to_string(),
            why: board_words(&control::Error::from(e)),
        }),
    }
}

/// A pose text that the firmware's parser read as something else.
const NOT_A_POSE: &str = "not six numbers x y z roll pitch yaw";

/// A pose the platform cannot take.
fn refused(summary: &str, words: &str) -> String {
    format!("{summary}\nthe platform cannot take this pose: {words}")
}
