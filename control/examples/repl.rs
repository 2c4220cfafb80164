//! Talk to the controller on the host: `cargo run -p control --example repl`.
//!
//! Reads stdin byte by byte (your terminal sends whole lines), writes the controller's output
//! to stdout, and after each line runs servo frames until the platform stands still (simulated
//! time, no waiting), printing how many frames that took. `save` writes to a flash kept in
//! memory (gone when the program ends).
use std::io::{Read, Write};

fn main() {
    let mut flash = control::store::RamFlash::new();
    let mut ctl: control::Controller =
        control::Controller::power_up(control::store::Store::load(&mut flash));
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
        // A command's work (and a save's flash write) to its end, as the board does it.
        while ctl.is_busy() {
            if let Some(write) = ctl.take_flash_write() {
                ctl.flash_written(write.perform(&mut flash));
            } else {
                ctl.work(&mut terminal, &mut out);
            }
        }
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
