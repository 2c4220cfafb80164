//! The view's web server (`std::net`, a thread per connection, 127.0.0.1 only), serving what
//! `./dev run`'s server serves at the same addresses, so the page is one for both: the page
//! (`/`, `/view/...`: embedded in the tool at build time), three.js and xterm.js
//! (`/vendor/three/...`, `/vendor/xterm/...`) and the kinematics (`/view-kinematics.wasm`),
//! read from the checkout the tool was built in ([`Assets`]); the event stream (`/events`,
//! Server-Sent Events: `hello`, `listing`, `uart`, `pins`, `stopped`); a line typed on the
//! page (`POST /uart`) and one of the page's own commands (`POST /command`, answered with the
//! board's reply). Only requests naming this server as their Host (and Origin, if any) are
//! answered, and the POSTs only as JSON, so no other web page can type on the board.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{TcpListener, TcpStream};
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Sender};
use std::sync::{Arc, Mutex};
use std::thread;
use std::time::Duration;

use super::json;
use super::pages::{lock, Job, Pages};
use crate::error::Error;

/// The page's own files, embedded by `build.rs` from `emulator/view/`.
mod page {
    include!(concat!(env!("OUT_DIR"), "/view_page.rs"));
}

/// Longest line the page may send, characters (the firmware refuses > 128 itself).
const MAX_PAGE_LINE: usize = 1024;
/// Longest request head or body read, bytes.
const MAX_REQUEST: usize = 16 * 1024;
/// How long a page's command may wait for the board's reply.
const COMMAND_TIMEOUT: Duration = Duration::from_secs(30);

/// Where the files the tool does not embed are: three.js and xterm.js (`npm ci` in
/// `emulator/`, as `./dev run` needs them) and the kinematics as WebAssembly (`cargo build -p
/// view-kinematics --release --target wasm32-unknown-unknown`, which `./dev run` does).
#[derive(Clone)]
pub struct Assets {
    /// `emulator/node_modules`.
    pub node_modules: PathBuf,
    /// `view_kinematics.wasm`.
    pub wasm: PathBuf,
}

impl Default for Assets {
    /// The checkout this tool was built from.
    fn default() -> Assets {
        let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
        Assets {
            node_modules: repo.join("emulator").join("node_modules"),
            wasm: repo
                .join("target")
                .join("wasm32-unknown-unknown")
                .join("release")
                .join("view_kinematics.wasm"),
        }
    }
}

impl Assets {
    /// What is missing, said with the command that makes it; `None` if all is there.
    pub fn missing(&self) -> Option<String> {
        if !self.node_modules.join("three").join("build").is_dir() {
            return Some(format!(
                "three.js is not in {} (run `npm ci` in emulator/, or ./dev run once)",
                self.node_modules.display()
            ));
        }
        if !self.wasm.is_file() {
            return Some(format!(
                "{} is not built (cargo build -p view-kinematics --release --target \
                 wasm32-unknown-unknown, or ./dev run once)",
                self.wasm.display()
            ));
        }
        None
    }
}

/// A listening server.
pub struct Server {
    listener: TcpListener,
    /// The port it listens on.
    pub port: u16,
}

impl Server {
    /// Listens on 127.0.0.1:`port` (0: any free port; a taken port falls back to any free one
    /// when `fallback`).
    pub fn bind(port: u16, fallback: bool) -> Result<Server, Error> {
        let listener = match TcpListener::bind(("127.0.0.1", port)) {
            Ok(listener) => listener,
            Err(e) if fallback && port != 0 && e.kind() == std::io::ErrorKind::AddrInUse => {
                TcpListener::bind(("127.0.0.1", 0)).map_err(|e| listen_error(0, &e))?
            }
            Err(e) => return Err(listen_error(port, &e)),
        };
        let port = listener
            .local_addr()
            .map_err(|e| listen_error(port, &e))?
            .port();
        Ok(Server { listener, port })
    }

    /// The page's address.
    pub fn url(&self) -> String {
        format!("http://127.0.0.1:{}/", self.port)
    }
}

fn listen_error(port: u16, e: &std::io::Error) -> Error {
    Error::View {
        doing: format!("listen on 127.0.0.1:{port}"),
        why: e.to_string(),
    }
}

/// Serves pages until the process ends: each connection in a thread of its own.
pub fn serve(server: Server, assets: Assets, jobs: Sender<Job>, pages: Arc<Mutex<Pages>>) {
    let port = server.port;
    for stream in server.listener.incoming().flatten() {
        let (assets, jobs, pages) = (assets.clone(), jobs.clone(), Arc::clone(&pages));
        thread::spawn(move || {
            let _ = Connection {
                port,
                assets,
                jobs,
                pages,
            }
            .handle(stream);
        });
    }
}

struct Connection {
    port: u16,
    assets: Assets,
    jobs: Sender<Job>,
    pages: Arc<Mutex<Pages>>,
}

/// A request's head: method, path, and the headers the server looks at.
struct Request {
    method: String,
    path: String,
    host: Option<String>,
    origin: Option<String>,
    content_type: Option<String>,
    length: usize,
}

fn read_head(reader: &mut impl BufRead) -> Option<Request> {
    let mut first = String::new();
    reader.read_line(&mut first).ok()?;
    let mut parts = first.split_whitespace();
    let (method, path) = (parts.next()?.to_string(), parts.next()?.to_string());
    let mut request = Request {
        method,
        path,
        host: None,
        origin: None,
        content_type: None,
        length: 0,
    };
    let mut read = first.len();
    loop {
        let mut line = String::new();
        read += reader.read_line(&mut line).ok()?;
        if read > MAX_REQUEST || line.is_empty() {
            return None;
        }
        let line = line.trim_end();
        if line.is_empty() {
            return Some(request);
        }
        let (name, value) = line.split_once(':')?;
        let value = value.trim().to_string();
        match name.trim().to_ascii_lowercase().as_str() {
            "host" => request.host = Some(value),
            "origin" => request.origin = Some(value),
            "content-type" => request.content_type = Some(value),
            "content-length" => request.length = value.parse().ok()?,
            _ => {}
        }
    }
}

impl Connection {
    fn handle(self, stream: TcpStream) -> std::io::Result<()> {
        let mut reader = BufReader::new(stream.try_clone()?);
        let mut out = stream;
        let Some(request) = read_head(&mut reader) else {
            return respond(&mut out, 400, "text/plain", b"bad request\n");
        };
        let hosts = [
            format!("127.0.0.1:{}", self.port),
            format!("localhost:{}", self.port),
        ];
        if !request.host.as_ref().is_some_and(|h| hosts.contains(h)) {
            return respond(&mut out, 403, "text/plain", b"forbidden host\n");
        }
        let path = request
            .path
            .split('?')
            .next()
            .unwrap_or_default()
            .to_string();
        match (request.method.as_str(), path.as_str()) {
            ("POST", "/uart" | "/command") => {
                if request.length > MAX_REQUEST {
                    return respond(&mut out, 413, "text/plain", b"too long\n");
                }
                let mut body = vec![0; request.length];
                reader.read_exact(&mut body)?;
                self.post(&mut out, &request, &path, &body)
            }
            ("GET" | "HEAD", "/events") => self.events(out),
            ("GET" | "HEAD", _) => self.file(&mut out, &path),
            _ => respond(&mut out, 405, "text/plain", b"method not allowed\n"),
        }
    }

    fn post(
        &self,
        out: &mut TcpStream,
        request: &Request,
        path: &str,
        body: &[u8],
    ) -> std::io::Result<()> {
        let own = format!("http://{}", request.host.as_deref().unwrap_or_default());
        if request.origin.as_ref().is_some_and(|o| *o != own) {
            return respond(out, 403, "text/plain", b"forbidden origin\n");
        }
        // JSON only: a cross-site form or simple request cannot send it without asking first.
        if !request
            .content_type
            .as_deref()
            .unwrap_or_default()
            .starts_with("application/json")
        {
            return respond(out, 415, "text/plain", b"send JSON\n");
        }
        let Some(line) = json::string_field(&String::from_utf8_lossy(body), "line") else {
            return respond(out, 400, "text/plain", b"not JSON with a line\n");
        };
        if line.chars().count() > MAX_PAGE_LINE || line.contains(['\r', '\n']) {
            let why = format!("one line of at most {MAX_PAGE_LINE} characters\n");
            return respond(out, 400, "text/plain", why.as_bytes());
        }
        if let Some(reason) = &lock(&self.pages).stopped {
            return respond(out, 503, "text/plain", format!("{reason}\n").as_bytes());
        }
        if path == "/uart" {
            let _ = self.jobs.send(Job::Typed(line));
            return respond(out, 200, "application/json", b"{\"held\":false}");
        }
        let (answer, reply) = mpsc::channel();
        let _ = self.jobs.send(Job::Command(line, answer));
        match reply.recv_timeout(COMMAND_TIMEOUT) {
            Ok(reply) => {
                let body = format!(
                    "{{\"reply\":{},\"data\":{}}}",
                    json::string(&reply.last),
                    json::strings(&reply.data)
                );
                respond(out, 200, "application/json", body.as_bytes())
            }
            Err(_) => respond(out, 503, "text/plain", b"the board did not answer\n"),
        }
    }

    fn events(&self, mut out: TcpStream) -> std::io::Result<()> {
        out.write_all(
            b"HTTP/1.1 200 OK\r\nContent-Type: text/event-stream\r\nCache-Control: no-store\r\n\
              Connection: keep-alive\r\n\r\n",
        )?;
        let queue = lock(&self.pages).join();
        // Ends when the page goes (a write fails) or the link stopped (the queue closes).
        for message in queue {
            out.write_all(message.as_bytes())?;
        }
        Ok(())
    }

    fn file(&self, out: &mut TcpStream, path: &str) -> std::io::Result<()> {
        if path.contains("..") || path.contains('\\') || path.contains('%') {
            return respond(out, 404, "text/plain", b"not found\n");
        }
        let name = if path == "/" || path == "/index.html" {
            "/view/index.html"
        } else {
            path
        };
        if let Some(file) = name.strip_prefix("/view/") {
            return match page::PAGE.iter().find(|(n, _)| *n == file) {
                Some((n, bytes)) => respond(out, 200, content_type(n), bytes),
                None => respond(out, 404, "text/plain", b"not found\n"),
            };
        }
        let on_disk = if name == "/view-kinematics.wasm" {
            Some(self.assets.wasm.clone())
        } else if let Some(rest) = name.strip_prefix("/vendor/three/") {
            ["build/", "examples/jsm/"]
                .iter()
                .any(|sub| rest.starts_with(sub))
                .then(|| self.assets.node_modules.join("three").join(rest))
        } else if let Some(rest) = name.strip_prefix("/vendor/xterm/") {
            ["lib/", "css/"]
                .iter()
                .any(|sub| rest.starts_with(sub))
                .then(|| {
                    self.assets
                        .node_modules
                        .join("@xterm")
                        .join("xterm")
                        .join(rest)
                })
        } else {
            None
        };
        match on_disk.map(std::fs::read) {
            Some(Ok(bytes)) => respond(out, 200, content_type(name), &bytes),
            _ => respond(out, 404, "text/plain", b"not found\n"),
        }
    }
}

fn content_type(name: &str) -> &'static str {
    let ext = name.rsplit('.').next().unwrap_or_default();
    match ext {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "wasm" => "application/wasm",
        "map" => "application/json",
        _ => "application/octet-stream",
    }
}

fn respond(out: &mut TcpStream, status: u16, kind: &str, body: &[u8]) -> std::io::Result<()> {
    let reason = match status {
        200 => "OK",
        400 => "Bad Request",
        403 => "Forbidden",
        404 => "Not Found",
        405 => "Method Not Allowed",
        413 => "Payload Too Large",
        415 => "Unsupported Media Type",
        _ => "Service Unavailable",
    };
    write!(
        out,
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    out.write_all(body)?;
    out.flush()
}
