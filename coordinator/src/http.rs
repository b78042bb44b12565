//! The live view's HTTP server (`run --http ADDR`; the only module that knows HTTP, with
//! `tiny_http`): `GET /` the page ([`crate::live_page`]), `GET /status.json` the [`Status`]
//! as JSON. Served by its own threads from snapshots of [`Live`], so a slow or stuck client
//! never holds up the coordinator loop; it answers only GET (and HEAD), never writes anything.

use std::net::SocketAddr;
use std::sync::Arc;

use crate::live::Live;

/// Threads answering requests (a stuck client holds one).
const THREADS: usize = 2;

/// A running server; dropping it stops the threads.
pub struct LiveServer {
    server: Arc<tiny_http::Server>,
    addr: SocketAddr,
    threads: Vec<std::thread::JoinHandle<()>>,
}

impl std::fmt::Debug for LiveServer {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LiveServer")
            .field("addr", &self.addr)
            .finish()
    }
}

impl LiveServer {
    /// Where it listens (the port the system chose for port 0).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        for _ in 0..self.threads.len() {
            self.server.unblock();
        }
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// Parses `--http`'s value: `PORT` (on loopback), `HOST:PORT` or `[V6]:PORT`.
pub fn parse_addr(s: &str) -> Result<SocketAddr, String> {
    let s = s.trim();
    if let Ok(port) = s.parse::<u16>() {
        return Ok(SocketAddr::from(([127, 0, 0, 1], port)));
    }
    if let Ok(a) = s.parse::<SocketAddr>() {
        return Ok(a);
    }
    use std::net::ToSocketAddrs;
    match s.to_socket_addrs() {
        Ok(mut it) => it.next().ok_or_else(|| format!("'{s}' names no address")),
        Err(_) => Err(format!(
            "'{s}' is not an address to serve on; write a port (8080, on loopback), 127.0.0.1:8080, or 0.0.0.0:8080 to be reached from other machines"
        )),
    }
}

/// Serves `live` on `addr` until the returned server is dropped.
pub fn serve(addr: SocketAddr, live: Arc<Live>) -> Result<LiveServer, String> {
    let server = tiny_http::Server::http(addr)
        .map_err(|e| format!("cannot serve the live view on {addr}: {e} (choose another port, or 0 for any free one)"))?;
    let bound = server
        .server_addr()
        .to_ip()
        .ok_or_else(|| format!("the live view's server on {addr} has no IP address"))?;
    let server = Arc::new(server);
    let mut threads = Vec::new();
    for _ in 0..THREADS {
        let server = Arc::clone(&server);
        let live = Arc::clone(&live);
        let t = floorcast_worker::spawn_thread(move || {
            while let Ok(req) = server.recv() {
                answer(req, &live);
            }
        })
        .map_err(|e| format!("cannot start the live view's threads: {e}"))?;
        threads.push(t);
    }
    Ok(LiveServer {
        server,
        addr: bound,
        threads,
    })
}

fn header(name: &str, value: &str) -> tiny_http::Header {
    // Both are ASCII constants of this module.
    tiny_http::Header::from_bytes(name.as_bytes(), value.as_bytes())
        .unwrap_or_else(|()| unreachable!("constant header {name}"))
}

/// One request: the page, the JSON, or 404/405.
fn answer(req: tiny_http::Request, live: &Live) {
    use tiny_http::Method;
    let path = req.url().split('?').next().unwrap_or("").to_string();
    let (code, kind, body) = match (req.method(), path.as_str()) {
        (Method::Get | Method::Head, "/") => (
            200,
            "text/html; charset=utf-8",
            crate::live_page::page(&live.snapshot()),
        ),
        (Method::Get | Method::Head, "/status.json") => (
            200,
            "application/json",
            serde_json::to_string_pretty(&live.snapshot()).unwrap_or_default(),
        ),
        (Method::Get | Method::Head, _) => (
            404,
            "text/plain; charset=utf-8",
            "not found: the live view serves / and /status.json\n".to_string(),
        ),
        _ => (
            405,
            "text/plain; charset=utf-8",
            "only GET: the live view changes nothing\n".to_string(),
        ),
    };
    let resp = tiny_http::Response::from_string(body)
        .with_status_code(code)
        .with_header(header("Content-Type", kind))
        .with_header(header("Cache-Control", "no-store"));
    // A client gone before the answer is not the coordinator's problem.
    let _ = req.respond(resp);
}
