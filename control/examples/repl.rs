//! Talk to the controller on the host: `cargo run -p control --example repl`.
//!
//! Reads stdin byte by byte (your terminal sends whole lines), writes the controller's output
//! to stdout, and after each line runs servo frames until the platform stands still (simulated
//! time, no waiting), printing how many frames that took.
use std::io::{Read, Write};

fn main() {
    let mut ctl = control::Controller::new(control::Settings::default());
    let mut terminal = control::Session::new();
    let mut out = String::new();
    ctl.banner(&mut terminal, &mut out);
    let stdout = std::io::stdout();
    let mut stdout = stdout.lock();
    let _ = stdout.write_all(out.as_bytes());
    let _ = stdout.flush();
    for byte in std::io::stdin().lock().bytes() {
        let Ok(byte) = byte else { break };
        out.clear();
        ctl.on_byte(&mut terminal, byte, &mut out);
        if byte == b'\n' || byte == b'\r' {
            let mut frames = 0u32;
            while ctl.is_moving() && frames < 10_000_000 {
                ctl.on_frame();
                frames += 1;
            }
            ctl.on_frame();
            if frames > 0 {
                // Before the prompt, if there is one.
                let prompt = out.ends_with("> ");
                if prompt {
                    out.truncate(out.len() - 2);
                }
                out.push_str(&format!("[simulated {frames} frames]\r\n"));
                if prompt {
                    out.push_str("> ");
                }
            }
            ctl.write_notices(&mut terminal, &mut out);
        }
        let _ = stdout.write_all(out.as_bytes());
        let _ = stdout.flush();
    }
}
