//! The live view's HTTP server (`run --http ADDR`; the only module that knows HTTP):
//! `GET /` the page ([`crate::live_page`]), `GET /status.json` the [`Status`](crate::live::Status)
//! as JSON. Served by its own threads from snapshots of [`Live`], so a slow or stuck client
//! never holds up the coordinator loop; it answers only GET (and HEAD), never writes anything.
//!
//! Written over `std::net` (HTTP/1.0 and 1.1, keep-alive, no request bodies) so that every
//! thing a client controls is bounded ([`Limits`], said in docs/live-view.md): the size and
//! count of a request's header lines (431 beyond), the time to send a request (408), the time
//! a connection may stay idle, the time to take an answer, and the number of connections
//! (503 beyond). Dropping the [`LiveServer`] closes every connection at once, so a finished
//! `run` never waits for a client.

use std::collections::HashMap;
use std::io::{Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use crate::live::Live;

/// What a client may use of the server.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Bytes of a request's head (request line and header lines); beyond: 431.
    pub header_bytes: usize,
    /// Header lines of a request; beyond: 431.
    pub header_lines: usize,
    /// From a request's first byte to the end of its head; beyond: 408 and closed.
    pub request_time: Duration,
    /// A connection with no request under way is closed after this long.
    pub idle_time: Duration,
    /// An answer not taken by the client within this long closes the connection.
    pub write_time: Duration,
    /// Connections open at once; more are answered 503 and closed.
    pub connections: usize,
}

impl Default for Limits {
    fn default() -> Limits {
        Limits {
            header_bytes: 16 * 1024,
            header_lines: 64,
            request_time: Duration::from_secs(5),
            idle_time: Duration::from_secs(5),
            write_time: Duration::from_secs(5),
            connections: 32,
        }
    }
}

/// How often the accepting thread looks whether the server is being stopped.
const POLL: Duration = Duration::from_millis(20);

/// The open connections (a clone of each socket, to close them all when the server stops).
#[derive(Default)]
struct Open {
    next: AtomicU64,
    streams: Mutex<HashMap<u64, TcpStream>>,
}

impl Open {
    fn lock(&self) -> std::sync::MutexGuard<'_, HashMap<u64, TcpStream>> {
        self.streams.lock().unwrap_or_else(|p| p.into_inner())
    }
}

/// A connection's place in [`Open`], given back however its thread ends.
struct Registered {
    open: Arc<Open>,
    id: u64,
}

impl Drop for Registered {
    fn drop(&mut self) {
        self.open.lock().remove(&self.id);
    }
}

/// A running server; dropping it stops it and closes every connection.
pub struct LiveServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    open: Arc<Open>,
    accept: Option<std::thread::JoinHandle<()>>,
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

    /// Connections open now.
    pub fn connections(&self) -> usize {
        self.open.lock().len()
    }
}

impl Drop for LiveServer {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        // The accepting thread sees `stop` within POLL; after it no connection is added.
        if let Some(t) = self.accept.take() {
            let _ = t.join();
        }
        // Every connection's thread then fails its read or write at once and ends.
        for s in self.open.lock().values() {
            let _ = s.shutdown(Shutdown::Both);
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

/// Serves `live` on `addr` with the default [`Limits`] until the returned server is dropped.
pub fn serve(addr: SocketAddr, live: Arc<Live>) -> Result<LiveServer, String> {
    serve_with(addr, live, Limits::default())
}

/// [`serve`] with other limits (tests use short times).
pub fn serve_with(addr: SocketAddr, live: Arc<Live>, limits: Limits) -> Result<LiveServer, String> {
    let listener = TcpListener::bind(addr).map_err(|e| {
        format!("cannot serve the live view on {addr}: {e} (choose another port, or 0 for any free one)")
    })?;
    let bound = listener
        .local_addr()
        .map_err(|e| format!("the live view's server on {addr} has no address: {e}"))?;
    listener
        .set_nonblocking(true)
        .map_err(|e| format!("cannot serve the live view on {addr}: {e}"))?;
    let stop = Arc::new(AtomicBool::new(false));
    let open = Arc::new(Open::default());
    let accept = {
        let (stop, open) = (Arc::clone(&stop), Arc::clone(&open));
        floorcast_worker::spawn_thread(move || accept_loop(&listener, &live, limits, &stop, &open))
            .map_err(|e| format!("cannot start the live view's thread: {e}"))?
    };
    Ok(LiveServer {
        addr: bound,
        stop,
        open,
        accept: Some(accept),
    })
}

fn accept_loop(
    listener: &TcpListener,
    live: &Arc<Live>,
    limits: Limits,
    stop: &AtomicBool,
    open: &Arc<Open>,
) {
    while !stop.load(Ordering::SeqCst) {
        let stream = match listener.accept() {
            Ok((s, _)) => s,
            Err(e) if e.kind() == std::io::ErrorKind::WouldBlock => {
                std::thread::sleep(POLL);
                continue;
            }
            // A connection reset before it was accepted, or no file descriptor left: the
            // next one may work.
            Err(_) => {
                std::thread::sleep(POLL);
                continue;
            }
        };
        let _ = stream.set_nonblocking(false);
        let _ = stream.set_write_timeout(Some(limits.write_time));
        let _ = stream.set_nodelay(true);
        let registered = {
            let mut streams = open.lock();
            match (streams.len() < limits.connections, stream.try_clone()) {
                (true, Ok(clone)) => {
                    let id = open.next.fetch_add(1, Ordering::SeqCst);
                    streams.insert(id, clone);
                    Some(Registered {
                        open: Arc::clone(open),
                        id,
                    })
                }
                _ => None,
            }
        };
        let Some(registered) = registered else {
            refuse_busy(stream, limits);
            continue;
        };
        let live = Arc::clone(live);
        // No thread to be had: the connection is closed (dropped with the closure).
        let _ = floorcast_worker::spawn_thread(move || {
            let _registered = registered;
            connection(stream, &live, limits);
        });
    }
}

/// A connection beyond [`Limits::connections`]: 503, closed (a fresh socket's buffer takes
/// the few bytes without blocking; the write timeout bounds it anyway).
fn refuse_busy(mut stream: TcpStream, limits: Limits) {
    let _ = stream.set_write_timeout(Some(limits.write_time.min(Duration::from_secs(1))));
    let body = format!(
        "the live view serves {} connections at once; try again in a few seconds\n",
        limits.connections
    );
    let _ = stream.write_all(&head(503, "text/plain; charset=utf-8", body.len(), false));
    let _ = stream.write_all(body.as_bytes());
    let _ = stream.shutdown(Shutdown::Both);
}

/// A request's head as read: what the answer needs.
#[derive(Debug, PartialEq, Eq)]
struct Request {
    method: String,
    path: String,
    keep_alive: bool,
}

/// Why a connection ends without a request to answer.
#[derive(Debug, PartialEq, Eq)]
enum End {
    /// Closed by the client, idle too long, or the server stopping: close quietly.
    Quiet,
    /// Answer with this status and text, then close.
    Refuse(u16, &'static str),
}

/// Requests on one connection until it ends.
fn connection(mut stream: TcpStream, live: &Live, limits: Limits) {
    let mut buf: Vec<u8> = Vec::with_capacity(1024);
    loop {
        match read_request(&mut stream, &mut buf, limits) {
            Ok(req) => {
                if answer(&mut stream, &req, live).is_err() || !req.keep_alive {
                    break;
                }
            }
            Err(End::Quiet) => break,
            Err(End::Refuse(code, text)) => {
                let _ =
                    stream.write_all(&head(code, "text/plain; charset=utf-8", text.len(), false));
                let _ = stream.write_all(text.as_bytes());
                linger(&mut stream);
                break;
            }
        }
    }
    let _ = stream.shutdown(Shutdown::Both);
}

/// After a refusal: the answer's end is sent, and what the client is still sending read and
/// dropped for a moment (at most 256 KB, half a second), so that closing with unread bytes
/// (which resets the connection) does not drop the answer before the client reads it.
fn linger(stream: &mut TcpStream) {
    let _ = stream.shutdown(Shutdown::Write);
    let until = Instant::now() + Duration::from_millis(500);
    let mut chunk = [0u8; 4096];
    let mut left = 256 * 1024usize;
    while left > 0 {
        let wait = until.saturating_duration_since(Instant::now());
        if wait.is_zero() || stream.set_read_timeout(Some(wait)).is_err() {
            return;
        }
        match stream.read(&mut chunk) {
            Ok(0) | Err(_) => return,
            Ok(n) => left = left.saturating_sub(n),
        }
    }
}

/// Reads one request's head into `buf` (which may hold the start of it already, sent along
/// with the previous request) within the limits, and takes it out of `buf`.
fn read_request(stream: &mut TcpStream, buf: &mut Vec<u8>, limits: Limits) -> Result<Request, End> {
    let idle_until = Instant::now() + limits.idle_time;
    let mut request_until = (!buf.is_empty()).then(|| Instant::now() + limits.request_time);
    let mut chunk = [0u8; 4096];
    let end = loop {
        if let Some(end) = head_end(buf) {
            break end;
        }
        if buf.len() > limits.header_bytes {
            return Err(End::Refuse(
                431,
                "request header too large: the live view reads at most 16 KB of header\n",
            ));
        }
        let (until, on_timeout) = match request_until {
            Some(t) => (t, End::Refuse(408, "request not sent in time\n")),
            None => (idle_until, End::Quiet),
        };
        let left = until.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(on_timeout);
        }
        let _ = stream.set_read_timeout(Some(left));
        // Never more than one byte past the limit, so the buffer stays bounded.
        let room = (limits.header_bytes + 1 - buf.len()).min(chunk.len());
        match stream.read(&mut chunk[..room]) {
            Ok(0) => return Err(End::Quiet),
            Ok(n) => {
                buf.extend_from_slice(&chunk[..n]);
                request_until.get_or_insert_with(|| Instant::now() + limits.request_time);
            }
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
            Err(e)
                if matches!(
                    e.kind(),
                    std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                ) =>
            {
                return Err(on_timeout)
            }
            Err(_) => return Err(End::Quiet),
        }
    };
    if end > limits.header_bytes {
        return Err(End::Refuse(
            431,
            "request header too large: the live view reads at most 16 KB of header\n",
        ));
    }
    let head: Vec<u8> = buf.drain(..end).collect();
    parse_head(&head, limits)
}

/// Where the head ends in `buf` (after its blank line; a bare LF is taken for CRLF).
fn head_end(buf: &[u8]) -> Option<usize> {
    let mut i = 0;
    while let Some(p) = buf[i..].iter().position(|&b| b == b'\n') {
        let nl = i + p;
        let rest = &buf[nl + 1..];
        if rest.first() == Some(&b'\n') {
            return Some(nl + 2);
        }
        if rest.starts_with(b"\r\n") {
            return Some(nl + 3);
        }
        i = nl + 1;
    }
    None
}

fn parse_head(head: &[u8], limits: Limits) -> Result<Request, End> {
    const BAD: End = End::Refuse(
        400,
        "bad request: the live view answers GET / and GET /status.json\n",
    );
    let text = std::str::from_utf8(head).map_err(|_| BAD)?;
    let mut lines = text.lines().map(|l| l.strip_suffix('\r').unwrap_or(l));
    let first = lines.next().ok_or(BAD)?;
    let mut parts = first.split(' ');
    let (Some(method), Some(target), Some(version), None) =
        (parts.next(), parts.next(), parts.next(), parts.next())
    else {
        return Err(BAD);
    };
    let mut keep_alive = match version {
        "HTTP/1.1" => true,
        "HTTP/1.0" => false,
        _ => {
            return Err(End::Refuse(
                505,
                "HTTP version not supported: use HTTP/1.0 or HTTP/1.1\n",
            ))
        }
    };
    let mut count = 0;
    for line in lines.filter(|l| !l.is_empty()) {
        count += 1;
        if count > limits.header_lines {
            return Err(End::Refuse(
                431,
                "too many header lines: the live view reads at most 64\n",
            ));
        }
        let (name, value) = line.split_once(':').ok_or(BAD)?;
        let value = value.trim();
        if name.eq_ignore_ascii_case("connection") {
            if value.eq_ignore_ascii_case("close") {
                keep_alive = false;
            }
        } else if name.eq_ignore_ascii_case("transfer-encoding")
            || (name.eq_ignore_ascii_case("content-length") && value != "0")
        {
            // A body is never read: the connection cannot go on after it.
            keep_alive = false;
        }
    }
    if method != "GET" && method != "HEAD" {
        keep_alive = false;
    }
    Ok(Request {
        method: method.to_string(),
        path: target.split('?').next().unwrap_or("").to_string(),
        keep_alive,
    })
}

fn reason(code: u16) -> &'static str {
    match code {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        405 => "Method Not Allowed",
        408 => "Request Timeout",
        431 => "Request Header Fields Too Large",
        503 => "Service Unavailable",
        505 => "HTTP Version Not Supported",
        _ => "",
    }
}

/// An answer's status line and headers.
fn head(code: u16, kind: &str, len: usize, keep_alive: bool) -> Vec<u8> {
    let mut h = format!(
        "HTTP/1.1 {code} {}\r\nContent-Type: {kind}\r\nContent-Length: {len}\r\nCache-Control: no-store\r\nConnection: {}\r\n",
        reason(code),
        if keep_alive { "keep-alive" } else { "close" }
    );
    if code == 405 {
        h.push_str("Allow: GET, HEAD\r\n");
    }
    h.push_str("\r\n");
    h.into_bytes()
}

/// One request: the page, the JSON, or 404/405.
fn answer(stream: &mut TcpStream, req: &Request, live: &Live) -> std::io::Result<()> {
    let get = req.method == "GET" || req.method == "HEAD";
    let (code, kind, body) = match (get, req.path.as_str()) {
        (true, "/") => (
            200,
            "text/html; charset=utf-8",
            crate::live_page::page(&live.snapshot()),
        ),
        (true, "/status.json") => (
            200,
            "application/json",
            serde_json::to_string_pretty(&live.snapshot()).unwrap_or_default(),
        ),
        (true, _) => (
            404,
            "text/plain; charset=utf-8",
            "not found: the live view serves / and /status.json\n".to_string(),
        ),
        (false, _) => (
            405,
            "text/plain; charset=utf-8",
            "only GET: the live view changes nothing\n".to_string(),
        ),
    };
    let mut out = head(code, kind, body.len(), req.keep_alive);
    if req.method != "HEAD" {
        out.extend_from_slice(body.as_bytes());
    }
    stream.write_all(&out)?;
    stream.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn quick() -> Limits {
        Limits {
            request_time: Duration::from_millis(600),
            idle_time: Duration::from_millis(600),
            write_time: Duration::from_millis(600),
            connections: 4,
            ..Limits::default()
        }
    }

    fn start(limits: Limits) -> LiveServer {
        let live = Arc::new(Live::new("unit"));
        serve_with(SocketAddr::from(([127, 0, 0, 1], 0)), live, limits).unwrap()
    }

    fn connect(s: &LiveServer) -> TcpStream {
        let c = TcpStream::connect(s.addr()).unwrap();
        c.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
        c
    }

    /// Reads one answer: status code, headers (lower-cased names), body.
    fn read_answer(c: &mut TcpStream) -> (u16, Vec<(String, String)>, String) {
        let mut buf = Vec::new();
        let mut byte = [0u8; 1];
        while !buf.ends_with(b"\r\n\r\n") {
            assert_eq!(c.read(&mut byte).unwrap(), 1, "closed mid-head: {buf:?}");
            buf.push(byte[0]);
        }
        let text = String::from_utf8(buf).unwrap();
        let mut lines = text.lines();
        let code = lines
            .next()
            .unwrap()
            .split(' ')
            .nth(1)
            .unwrap()
            .parse()
            .unwrap();
        let headers: Vec<(String, String)> = lines
            .filter_map(|l| l.split_once(':'))
            .map(|(n, v)| (n.to_ascii_lowercase(), v.trim().to_string()))
            .collect();
        let len: usize = headers
            .iter()
            .find(|(n, _)| n == "content-length")
            .map(|(_, v)| v.parse().unwrap())
            .unwrap();
        let mut body = vec![0u8; len];
        c.read_exact(&mut body).unwrap();
        (code, headers, String::from_utf8(body).unwrap())
    }

    /// True when the server closed `c` (EOF or reset) within `within`.
    fn closed_within(c: &mut TcpStream, within: Duration) -> bool {
        c.set_read_timeout(Some(within)).unwrap();
        let mut b = [0u8; 1024];
        loop {
            match c.read(&mut b) {
                Ok(0) => return true,
                Ok(_) => continue,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                    ) =>
                {
                    return false
                }
                Err(_) => return true,
            }
        }
    }

    #[test]
    fn answers_by_method_and_path_and_keeps_the_connection() {
        let s = start(quick());
        let mut c = connect(&s);
        // (request, code, body contains, connection kept)
        let cases: [(&str, u16, &str, bool); 5] = [
            (
                "GET /status.json HTTP/1.1\r\nHost: x\r\n\r\n",
                200,
                "\"floorcast-status\"",
                true,
            ),
            (
                "GET /?x=1 HTTP/1.1\r\n\r\n",
                200,
                "<title>floorcast: unit",
                true,
            ),
            (
                "GET /nope HTTP/1.1\n\n",
                404,
                "serves / and /status.json",
                true,
            ),
            ("HEAD /status.json HTTP/1.1\r\n\r\n", 200, "", true),
            (
                "GET /status.json HTTP/1.1\r\nConnection: close\r\n\r\n",
                200,
                "floorcast-status",
                false,
            ),
        ];
        for (req, code, needle, kept) in cases.iter() {
            c.write_all(req.as_bytes()).unwrap();
            if req.starts_with("HEAD") {
                // No body follows a HEAD answer, whatever its Content-Length says.
                let mut buf = Vec::new();
                let mut byte = [0u8; 1];
                while !buf.ends_with(b"\r\n\r\n") {
                    c.read_exact(&mut byte).unwrap();
                    buf.push(byte[0]);
                }
                assert!(String::from_utf8(buf)
                    .unwrap()
                    .starts_with("HTTP/1.1 200 OK"));
                continue;
            }
            let (got, headers, body) = read_answer(&mut c);
            assert_eq!(got, *code, "{req:?}: {body}");
            assert!(body.contains(needle), "{req:?}: {body}");
            let conn = headers.iter().find(|(n, _)| n == "connection").unwrap();
            assert_eq!(conn.1 == "keep-alive", *kept, "{req:?}");
        }
        assert!(closed_within(&mut c, Duration::from_secs(2)));
        // One connection per request, each closed after its answer.
        for (req, code) in [
            (
                "POST /status.json HTTP/1.1\r\nContent-Length: 5\r\n\r\nhello",
                405,
            ),
            ("GET / HTTP/2.0\r\n\r\n", 505),
            ("GET /\r\n\r\n", 400),
            ("GET / HTTP/1.1\r\nno colon here\r\n\r\n", 400),
            ("GET /status.json HTTP/1.0\r\n\r\n", 200),
        ] {
            let mut c = connect(&s);
            c.write_all(req.as_bytes()).unwrap();
            let (got, headers, body) = read_answer(&mut c);
            assert_eq!(got, code, "{req:?}: {body}");
            assert!(
                headers.contains(&("connection".into(), "close".into())),
                "{req:?}"
            );
            assert!(closed_within(&mut c, Duration::from_secs(2)), "{req:?}");
        }
        // Two requests sent at once are both answered, in order.
        let mut c = connect(&s);
        c.write_all(b"GET /nope HTTP/1.1\r\n\r\nGET /status.json HTTP/1.1\r\n\r\n")
            .unwrap();
        assert_eq!(read_answer(&mut c).0, 404);
        assert_eq!(read_answer(&mut c).0, 200);
    }

    #[test]
    fn an_endless_or_crowded_header_is_refused_with_431_and_little_read() {
        let s = start(quick());
        // Endless: header lines without end, written until the server stops taking them.
        let mut c = connect(&s);
        c.write_all(b"GET / HTTP/1.1\r\n").unwrap();
        let line = format!("X-Fill: {}\r\n", "a".repeat(1000));
        let mut sent = 0usize;
        while sent < 64 << 20 {
            match c.write(line.as_bytes()) {
                Ok(n) => sent += n,
                Err(_) => break,
            }
        }
        // The kernel's buffers take some; the server stopped long before 64 MB.
        assert!(sent < 16 << 20, "{sent} bytes of header taken");
        // One line too long, in one piece: answered 431.
        let mut c = connect(&s);
        let long = format!(
            "GET / HTTP/1.1\r\nX-Long: {}\r\n\r\n",
            "b".repeat(20 * 1024)
        );
        c.write_all(long.as_bytes()).unwrap();
        assert_eq!(read_answer(&mut c).0, 431);
        // 65 short header lines: 431; 64 are fine.
        for (lines, code) in [(65, 431), (64, 200)] {
            let mut c = connect(&s);
            let mut req = "GET /status.json HTTP/1.1\r\n".to_string();
            for i in 0..lines {
                req.push_str(&format!("X-{i}: {i}\r\n"));
            }
            req.push_str("\r\n");
            c.write_all(req.as_bytes()).unwrap();
            assert_eq!(read_answer(&mut c).0, code, "{lines} header lines");
        }
    }

    #[test]
    fn slow_idle_and_surplus_clients_are_cut() {
        let limits = quick();
        let s = start(limits);
        // Slow: a request started and never finished is answered 408 after request_time.
        let mut slow = connect(&s);
        let t0 = Instant::now();
        slow.write_all(b"GET / HTTP/1.1\r\nHost: x\r\n").unwrap();
        assert_eq!(read_answer(&mut slow).0, 408);
        let took = t0.elapsed();
        assert!(
            took >= limits.request_time && took < Duration::from_secs(3),
            "{took:?}"
        );
        // A trickle (a byte every 100 ms) is cut at request_time all the same.
        let mut trickle = connect(&s);
        let t0 = Instant::now();
        let mut cut = false;
        for b in b"GET / HTTP/1.1\r\nX-Slow: "
            .iter()
            .chain([b'a'; 100].iter())
        {
            if trickle.write_all(&[*b]).is_err() {
                cut = true;
                break;
            }
            if t0.elapsed() > Duration::from_secs(3) {
                break;
            }
            std::thread::sleep(Duration::from_millis(100));
        }
        assert!(cut || closed_within(&mut trickle, Duration::from_millis(100)));
        assert!(t0.elapsed() < Duration::from_secs(3), "{:?}", t0.elapsed());
        // Idle: a connection that sends nothing, or nothing after its answer, is closed.
        let mut idle = connect(&s);
        let mut after = connect(&s);
        after.write_all(b"GET /nope HTTP/1.1\r\n\r\n").unwrap();
        assert_eq!(read_answer(&mut after).0, 404);
        let t0 = Instant::now();
        assert!(closed_within(&mut idle, Duration::from_secs(3)));
        assert!(closed_within(&mut after, Duration::from_secs(3)));
        assert!(t0.elapsed() < Duration::from_secs(2), "{:?}", t0.elapsed());
        // Surplus: with `connections` open, the next is answered 503 at once.
        let s = start(Limits {
            idle_time: Duration::from_secs(30),
            ..limits
        });
        let held: Vec<TcpStream> = (0..limits.connections).map(|_| connect(&s)).collect();
        let t0 = Instant::now();
        while s.connections() < limits.connections {
            assert!(
                t0.elapsed() < Duration::from_secs(2),
                "{} open",
                s.connections()
            );
            std::thread::sleep(Duration::from_millis(10));
        }
        let mut extra = connect(&s);
        let (code, _, body) = read_answer(&mut extra);
        assert_eq!(code, 503, "{body}");
        assert!(body.contains("4 connections at once"), "{body}");
        drop(held);
        // Once they are gone, a client is served again.
        let t0 = Instant::now();
        loop {
            let mut c = connect(&s);
            c.write_all(b"GET /status.json HTTP/1.1\r\n\r\n").unwrap();
            if read_answer(&mut c).0 == 200 {
                break;
            }
            assert!(t0.elapsed() < Duration::from_secs(3));
            std::thread::sleep(Duration::from_millis(50));
        }
    }

    #[test]
    fn dropping_the_server_closes_every_connection_at_once() {
        let s = start(Limits {
            idle_time: Duration::from_secs(600),
            request_time: Duration::from_secs(600),
            ..Limits::default()
        });
        let mut idle = connect(&s);
        let mut half = connect(&s);
        half.write_all(b"GET / HTTP/1.1\r\n").unwrap();
        let mut kept = connect(&s);
        kept.write_all(b"GET /status.json HTTP/1.1\r\n\r\n")
            .unwrap();
        assert_eq!(read_answer(&mut kept).0, 200);
        let addr = s.addr();
        let t0 = Instant::now();
        drop(s);
        assert!(t0.elapsed() < Duration::from_secs(1), "{:?}", t0.elapsed());
        for c in [&mut idle, &mut half, &mut kept] {
            assert!(closed_within(c, Duration::from_secs(1)));
        }
        assert!(TcpStream::connect(addr).is_err(), "still listening");
    }

    #[test]
    fn head_end_finds_the_blank_line() {
        for (buf, end) in [
            (&b"GET / HTTP/1.1\r\n\r\n"[..], Some(18)),
            (b"GET / HTTP/1.1\n\nrest", Some(16)),
            (b"GET / HTTP/1.1\r\nA: b\r\n\r\nGET", Some(24)),
            (b"GET / HTTP/1.1\r\nA: b\r\n", None),
            (b"", None),
        ] {
            assert_eq!(head_end(buf), end, "{:?}", String::from_utf8_lossy(buf));
        }
    }
}
