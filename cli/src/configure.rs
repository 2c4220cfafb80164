//! `init`, `apply`, `pull`, `send` and `shell`: a build file written, checked, sent to a board
//! and read back; lines sent to a board by hand or from a script.

use std::fs;
use std::io::{BufRead, IsTerminal, Write};
use std::path::Path;

use control::settings::Settings;

use crate::board;
use crate::build_file::{self, BuildFile};
use crate::link::{Link, Reply};
use crate::messages::{self, Problem};
use crate::sizing::Sizing;

/// Reads a whole text file.
pub fn read_text(path: &Path) -> Result<String, Problem> {
    fs::read_to_string(path).map_err(|error| Problem::File {
        path: path.display().to_string(),
        error,
    })
}

/// Writes a file; refuses to replace one unless `force`.
pub fn write_new(path: &Path, bytes: &[u8], force: bool) -> Result<(), Problem> {
    let file = if force {
        fs::File::create(path)
    } else {
        fs::File::create_new(path)
    };
    file.and_then(|mut f| f.write_all(bytes))
        .map_err(|error| Problem::File {
            path: path.display().to_string(),
            error,
        })
}

/// Reads and checks a build file.
pub fn read_build_file(path: &Path) -> Result<BuildFile, Problem> {
    build_file::parse(&path.display().to_string(), &read_text(path)?)
}

/// `init`: a commented build file of the default platform.
pub fn init(path: &Path, force: bool) -> Result<String, Problem> {
    let text = build_file::write(
        &Settings::default(),
        &Sizing::default(),
        messages::DEFAULT_PLATFORM,
    );
    write_new(path, text.as_bytes(), force)?;
    let name = path.display().to_string();
    Ok(messages::wrote_build_file(
        &name,
        messages::DEFAULT_PLATFORM,
    ))
}

/// `apply`: `defaults`, each `set` of the file in an order the board accepts, then `save`
/// (unless `save` is false); stops at the first refusal with the board's words.
pub fn apply(path: &Path, link: Option<&mut Link>, save: bool) -> Result<String, Problem> {
    let file = read_build_file(path)?;
    let name = path.display().to_string();
    let Some(link) = link else {
        return Ok(messages::build_file_good(&name, file.steps.len()));
    };
    link.start()?;
    link.request_ok("defaults")?;
    for step in &file.steps {
        let command = step.command();
        let reply = link.request(&command)?;
        if !reply.is_ok() {
            return Err(Problem::Refused {
                at: Some(format!("{name}:{}", step.line)),
                port: link.port().to_string(),
                line: command,
                reply: reply.last,
            });
        }
    }
    if save {
        link.request_ok("save")?;
    }
    Ok(messages::applied(
        &name,
        link.port(),
        file.steps.len(),
        save,
    ))
}

/// `pull`: the board's `config` as a build file.
pub fn pull(link: &mut Link, path: &Path, force: bool) -> Result<String, Problem> {
    link.start()?;
    let settings = board::read_settings(link)?;
    let source = messages::board_on(link.port());
    write_new(
        path,
        build_file::write(&settings, &Sizing::default(), &source).as_bytes(),
        force,
    )?;
    Ok(messages::wrote_build_file(
        &path.display().to_string(),
        &source,
    ))
}

/// Prints a reply as the board wrote it.
fn print_reply(out: &mut impl Write, reply: &Reply) {
    for line in reply.notices.iter().chain(&reply.data) {
        let _ = writeln!(out, "{}", messages::board_notice(line));
    }
    let _ = writeln!(out, "{}", reply.last);
}

/// `send`: each line, its reply printed; stops at the first refusal (an error naming it).
pub fn send(link: &mut Link, lines: &[String]) -> Result<(), Problem> {
    link.start()?;
    let mut out = std::io::stdout().lock();
    let from_stdin: Vec<String>;
    let lines = if lines.is_empty() {
        from_stdin = std::io::stdin()
            .lock()
            .lines()
            .collect::<Result<_, _>>()
            .map_err(|error| Problem::File {
                path: "standard input".into(),
                error,
            })?;
        &from_stdin
    } else {
        lines
    };
    for line in lines.iter().filter(|l| !l.trim().is_empty()) {
        let reply = link.request(line)?;
        print_reply(&mut out, &reply);
        if !reply.is_ok() {
            return Err(Problem::Refused {
                at: None,
                port: link.port().to_string(),
                line: line.clone(),
                reply: reply.last,
            });
        }
    }
    Ok(())
}

/// `shell`: lines typed (or piped) in, replies printed, until end of input. Refusals are
/// printed and the shell goes on.
pub fn shell(link: &mut Link) -> Result<(), Problem> {
    link.start()?;
    let stdin = std::io::stdin();
    let interactive = stdin.is_terminal();
    let mut out = std::io::stdout().lock();
    if interactive {
        let _ = writeln!(out, "{}", messages::shell_greeting(link.port()));
    }
    let mut input = stdin.lock();
    loop {
        if interactive {
            let _ = write!(out, "{}", messages::SHELL_PROMPT);
            let _ = out.flush();
        }
        let mut line = String::new();
        match input.read_line(&mut line) {
            Ok(0) => return Ok(()),
            Ok(_) => {}
            Err(error) => {
                return Err(Problem::File {
                    path: "standard input".into(),
                    error,
                })
            }
        }
        let line = line.trim_end_matches(['\r', '\n']);
        if line.trim().is_empty() {
            continue;
        }
        let reply = link.request(line)?;
        print_reply(&mut out, &reply);
    }
}
