//! `frond view`'s web server: serves an output folder on localhost so its preview page's live
//! view can load the GLBs beside it (browsers refuse a page opened from disk any read of its
//! neighbours). Read-only, GET and HEAD only, files inside the folder only; nothing is cached
//! (a rerun's files show on reload).
//!
//! Built on hyper (HTTP/1 only) over a single-threaded tokio runtime rather than by hand: the
//! server must hold up when a page of the folder, another local program or a hostile web page
//! talks to it, and hyper brings what that takes, tested by others — a total header-read
//! deadline, bounded header sizes, and request parsing that does not trust the client. On top:
//!
//! - **bounded connections**: at most [`MAX_CONNECTIONS`] are served at once (each a task, not a
//!   thread, so slow clients cost a few kilobytes each); a connection that sends no complete
//!   header within [`HEADER_TIMEOUT`], or whose response cannot write a byte for
//!   [`IO_TIMEOUT`], is closed.
//!   Accept errors (out of file descriptors) pause the loop briefly; the server never exits on
//!   a client's account;
//! - **files streamed** in 64 KiB chunks, never read whole;
//! - **nothing outside the folder**: the request path must be a plain relative name
//!   ([`crate::out_folder::checked_path`]), and the file is checked *after* it is opened: the
//!   opened file must be the one its canonical path names inside the folder (same device and
//!   inode), so swapping a link between the check and the open serves nothing;
//! - **a `Host` check**: only `127.0.0.1`, `localhost` and `[::1]` (with the bound port) are
//!   answered, so a web page that rebinds its own DNS name to 127.0.0.1 cannot read the folder;
//! - **no absolute paths** in any answer: the listing is titled with the folder's own name.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Duration;

use anyhow::{Context, Result, bail};
use bytes::Bytes;
use futures_util::StreamExt;
use http_body_util::{BodyExt, Empty, Full, StreamBody, combinators::BoxBody};
use hyper::body::Frame;
use hyper::{Method, Request, Response, StatusCode, header};
use tokio::sync::Semaphore;

use crate::out_folder::checked_path;

/// Connections served at once; more wait in the listen queue until one closes.
pub const MAX_CONNECTIONS: usize = 1024;
/// The whole request header must arrive within this, counted from the connection's start.
pub const HEADER_TIMEOUT: Duration = Duration::from_secs(10);
/// A response that cannot write a byte for this long is dropped (a stalled reader of a large
/// file).
pub const IO_TIMEOUT: Duration = Duration::from_secs(30);
/// Largest request head read (request line and headers).
const MAX_HEAD_BYTES: usize = 16 * 1024;
/// Chunk size files are streamed in.
const CHUNK: usize = 64 * 1024;

/// A bound server over one folder.
pub struct ViewServer {
    listener: std::net::TcpListener,
    root: PathBuf,
    start: String,
}

/// What every connection's handler shares.
struct Site {
    root: PathBuf,
    port: u16,
}

type Body = BoxBody<Bytes, std::io::Error>;

impl ViewServer {
    /// Binds `127.0.0.1:port` (0: any free port) over `root`, which must be a folder.
    pub fn bind(root: &Path, port: u16) -> Result<ViewServer> {
        let meta = std::fs::metadata(root)
            .with_context(|| format!("{}: cannot read the folder", root.display()))?;
        if !meta.is_dir() {
            bail!(
                "{}: not a folder (give frond lod's output folder)",
                root.display()
            );
        }
        let root = root
            .canonicalize()
            .with_context(|| format!("{}: cannot resolve the folder", root.display()))?;
        let listener = std::net::TcpListener::bind(("127.0.0.1", port)).with_context(|| {
            format!("cannot listen on 127.0.0.1:{port} (in use? port 0 picks a free one)")
        })?;
        let start = start_page(&root)?;
        Ok(ViewServer {
            listener,
            root,
            start,
        })
    }

    /// The address it listens on.
    pub fn addr(&self) -> Result<SocketAddr> {
        Ok(self.listener.local_addr()?)
    }

    /// The URL of the page to open: the folder's `index.html`, its one `*_preview.html`, or the
    /// folder's listing of preview pages.
    pub fn url(&self) -> Result<String> {
        Ok(format!("http://{}/{}", self.addr()?, self.start))
    }

    /// Serves until the process ends.
    pub fn serve(self) -> Result<()> {
        raise_open_file_limit();
        let runtime = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .max_blocking_threads(8)
            .build()
            .context("cannot start the server's runtime")?;
        let port = self.addr()?.port();
        let site = Arc::new(Site {
            root: self.root,
            port,
        });
        self.listener.set_nonblocking(true)?;
        runtime.block_on(async move {
            let listener = tokio::net::TcpListener::from_std(self.listener)?;
            accept_loop(listener, site).await;
            Ok(())
        })
    }
}

/// Accepts connections for ever, at most [`MAX_CONNECTIONS`] at once.
async fn accept_loop(listener: tokio::net::TcpListener, site: Arc<Site>) {
    let slots = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    loop {
        let Ok(permit) = slots.clone().acquire_owned().await else {
            return;
        };
        let stream = match listener.accept().await {
            Ok((stream, _)) => stream,
            Err(e) => {
                // Out of file descriptors, or a connection reset before it was accepted:
                // wait a moment (a busy loop would take the CPU) and go on.
                tracing::debug!("frond view: accept: {e}");
                tokio::time::sleep(Duration::from_millis(50)).await;
                continue;
            }
        };
        let site = site.clone();
        tokio::spawn(async move {
            serve_connection(stream, site).await;
            drop(permit);
        });
    }
}

/// Serves one connection (one request: no keep-alive) under the timeouts.
async fn serve_connection(stream: tokio::net::TcpStream, site: Arc<Site>) {
    // A write timeout only: while it sends a body, hyper keeps a read pending to notice the
    // client leave, and a read timeout would cut off any download longer than the timeout.
    // The request head has hyper's own deadline, which starts as the connection opens.
    let mut io = tokio_io_timeout::TimeoutStream::new(stream);
    io.set_write_timeout(Some(IO_TIMEOUT));
    let io = hyper_util::rt::TokioIo::new(Box::pin(io));
    let service = hyper::service::service_fn(move |req| {
        let site = site.clone();
        async move { Ok::<_, std::convert::Infallible>(answer(&site, &req).await) }
    });
    let result = hyper::server::conn::http1::Builder::new()
        .timer(hyper_util::rt::TokioTimer::new())
        .header_read_timeout(HEADER_TIMEOUT)
        .keep_alive(false)
        .max_buf_size(MAX_HEAD_BYTES)
        .serve_connection(io, service)
        .await;
    if let Err(e) = result {
        tracing::debug!("frond view: {e}");
    }
}

/// The answer to one request.
async fn answer(site: &Site, req: &Request<hyper::body::Incoming>) -> Response<Body> {
    if !host_allowed(req.headers().get(header::HOST), site.port) {
        return plain(StatusCode::MISDIRECTED_REQUEST, "unknown host");
    }
    let head = req.method() == Method::HEAD;
    if req.method() != Method::GET && !head {
        return plain(StatusCode::METHOD_NOT_ALLOWED, "GET or HEAD only");
    }
    let Some(rel) = decode_path(req.uri().path()) else {
        return plain(StatusCode::BAD_REQUEST, "bad path");
    };
    if rel.as_os_str().is_empty() {
        return match listing(&site.root) {
            Ok(page) => bytes_response("text/html; charset=utf-8", page.into_bytes(), head),
            Err(_) => plain(StatusCode::INTERNAL_SERVER_ERROR, "cannot list the folder"),
        };
    }
    match open_inside(&site.root, &rel) {
        Some((file, len)) => file_response(file, len, content_type(&rel), head),
        None => plain(StatusCode::NOT_FOUND, "not found"),
    }
}

/// Whether a request's `Host` names this server: 127.0.0.1, localhost or [::1], with the bound
/// port when a port is given.
fn host_allowed(host: Option<&header::HeaderValue>, port: u16) -> bool {
    let Some(host) = host.and_then(|h| h.to_str().ok()) else {
        return false;
    };
    let (name, given_port) = match host.rsplit_once(':') {
        Some((n, p)) if !p.contains(']') => (n, Some(p)),
        _ => (host, None),
    };
    let local = matches!(
        name.to_ascii_lowercase().as_str(),
        "127.0.0.1" | "localhost" | "[::1]"
    );
    local && given_port.is_none_or(|p| p.parse::<u16>() == Ok(port))
}

/// Opens `rel` inside `root` and checks what was opened (see the module doc): a regular file
/// whose canonical path lies in `root` and is the same file. Returns it with its length.
fn open_inside(root: &Path, rel: &Path) -> Option<(std::fs::File, u64)> {
    use std::os::unix::fs::MetadataExt;
    use std::os::unix::fs::OpenOptionsExt;
    let path = checked_path(root, rel).ok()?;
    // Non-blocking: opening a named pipe would otherwise wait for a writer, and with it the
    // whole server; it is then refused as not a regular file.
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(&path)
        .ok()?;
    let opened = file.metadata().ok()?;
    if !opened.is_file() {
        return None;
    }
    let canon = path.canonicalize().ok()?;
    let named = std::fs::metadata(&canon).ok()?;
    let same = named.dev() == opened.dev() && named.ino() == opened.ino();
    (canon.starts_with(root) && same).then_some((file, opened.len()))
}

/// A file streamed in [`CHUNK`]s.
fn file_response(file: std::fs::File, len: u64, kind: &str, head: bool) -> Response<Body> {
    let body: Body = if head {
        empty()
    } else {
        let reader = tokio::fs::File::from_std(file);
        let chunks = tokio_util::io::ReaderStream::with_capacity(reader, CHUNK);
        StreamBody::new(chunks.map(|c| c.map(Frame::data))).boxed()
    };
    response(StatusCode::OK, kind, len, body)
}

/// A response with a body held in memory (the listing, short messages).
fn bytes_response(kind: &str, bytes: Vec<u8>, head: bool) -> Response<Body> {
    let len = bytes.len() as u64;
    let body = if head {
        empty()
    } else {
        Full::new(Bytes::from(bytes))
            .map_err(|never| match never {})
            .boxed()
    };
    response(StatusCode::OK, kind, len, body)
}

/// A short plain-text answer.
fn plain(status: StatusCode, text: &'static str) -> Response<Body> {
    let body = Full::new(Bytes::from_static(text.as_bytes()))
        .map_err(|never| match never {})
        .boxed();
    response(status, "text/plain; charset=utf-8", text.len() as u64, body)
}

fn empty() -> Body {
    Empty::new().map_err(|never| match never {}).boxed()
}

fn response(status: StatusCode, kind: &str, len: u64, body: Body) -> Response<Body> {
    let mut r = Response::new(body);
    *r.status_mut() = status;
    let h = r.headers_mut();
    if let Ok(v) = header::HeaderValue::from_str(kind) {
        h.insert(header::CONTENT_TYPE, v);
    }
    h.insert(header::CONTENT_LENGTH, header::HeaderValue::from(len));
    h.insert(
        header::CACHE_CONTROL,
        header::HeaderValue::from_static("no-store"),
    );
    h.insert(
        header::X_CONTENT_TYPE_OPTIONS,
        header::HeaderValue::from_static("nosniff"),
    );
    r
}

/// Raises this process's soft limit of open files to its hard limit (at most 65,536), so
/// [`MAX_CONNECTIONS`] connections fit; where it cannot, accept errors pause the loop instead.
fn raise_open_file_limit() {
    let mut lim = libc::rlimit {
        rlim_cur: 0,
        rlim_max: 0,
    };
    // SAFETY: getrlimit/setrlimit with a valid pointer to an rlimit struct.
    unsafe {
        if libc::getrlimit(libc::RLIMIT_NOFILE, &mut lim) == 0 {
            let want = lim.rlim_max.min(65_536);
            if want > lim.rlim_cur {
                lim.rlim_cur = want;
                libc::setrlimit(libc::RLIMIT_NOFILE, &lim);
            }
        }
    }
}

/// The page `/` leads to (see [`ViewServer::url`]); empty for the generated listing.
fn start_page(root: &Path) -> Result<String> {
    if root.join("index.html").is_file() {
        return Ok("index.html".into());
    }
    let pages = preview_pages(root)?;
    Ok(match pages.as_slice() {
        [one] => one.clone(),
        _ => String::new(),
    })
}

/// The folder's `*_preview.html` files, sorted.
fn preview_pages(root: &Path) -> Result<Vec<String>> {
    let mut pages: Vec<String> = std::fs::read_dir(root)
        .with_context(|| format!("{}: cannot list the folder", root.display()))?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with("_preview.html"))
        .collect();
    pages.sort();
    Ok(pages)
}

/// A request path as a relative path inside the folder: percent-decoded, no `..`, no root.
fn decode_path(path: &str) -> Option<PathBuf> {
    let bytes = path.as_bytes();
    let mut decoded = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            decoded.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            decoded.push(bytes[i]);
            i += 1;
        }
    }
    let text = String::from_utf8(decoded).ok()?;
    if text.contains('\0') {
        return None;
    }
    let rel = PathBuf::from(text.trim_start_matches('/'));
    rel.components()
        .all(|c| matches!(c, std::path::Component::Normal(_)))
        .then_some(rel)
}

/// The listing `/` shows when the folder has no single page to open, titled with the folder's
/// own name (never its absolute path).
fn listing(root: &Path) -> Result<String> {
    let pages = preview_pages(root)?;
    let entries: Vec<frond_preview::index_page::IndexEntry> = pages
        .iter()
        .map(|p| frond_preview::index_page::IndexEntry {
            name: p.trim_end_matches("_preview.html").to_string(),
            page: Some(p.clone()),
            thumbnail: None,
            summary: p.clone(),
            failed: false,
        })
        .collect();
    let intro = if entries.is_empty() {
        "No preview pages here: run <code>frond lod</code> without <code>--no-preview</code> into \
         this folder."
            .to_string()
    } else {
        frond_preview::index_page::trees_line(entries.len(), None)
    };
    let title = root
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "frond".into());
    Ok(frond_preview::index_page::index_page(
        &title, &intro, &entries,
    ))
}

/// The media type of a file by its extension.
fn content_type(path: &Path) -> &'static str {
    match path.extension().and_then(|e| e.to_str()).unwrap_or("") {
        "html" => "text/html; charset=utf-8",
        "js" | "mjs" => "text/javascript; charset=utf-8",
        "css" => "text/css; charset=utf-8",
        "json" => "application/json",
        "wasm" => "application/wasm",
        "glb" => "model/gltf-binary",
        "gltf" => "model/gltf+json",
        "bin" => "application/octet-stream",
        "png" => "image/png",
        "jpg" | "jpeg" => "image/jpeg",
        "svg" => "image/svg+xml",
        "ktx2" => "image/ktx2",
        "csv" => "text/csv; charset=utf-8",
        "txt" | "md" => "text/plain; charset=utf-8",
        _ => "application/octet-stream",
    }
}

/// Opens `url` in the user's browser; false when no opener could be started.
pub fn open_browser(url: &str) -> bool {
    let mut cmd = if cfg!(target_os = "macos") {
        std::process::Command::new("open")
    } else if cfg!(windows) {
        let mut c = std::process::Command::new("cmd");
        c.args(["/C", "start", ""]);
        c
    } else {
        std::process::Command::new("xdg-open")
    };
    cmd.arg(url)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .is_ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn request_paths_stay_inside_the_folder() {
        assert_eq!(
            decode_path("/a%20b/c.png"),
            Some(PathBuf::from("a b/c.png"))
        );
        assert_eq!(decode_path("/"), Some(PathBuf::new()));
        assert_eq!(decode_path("/../etc/passwd"), None);
        assert_eq!(decode_path("/a/%2e%2e/%2e%2e/x"), None);
        assert_eq!(decode_path("/%zz"), None);
        assert_eq!(decode_path("/a%00b"), None);
    }

    #[test]
    fn engines_files_get_their_media_types() {
        assert_eq!(content_type(Path::new("x.wasm")), "application/wasm");
        assert_eq!(content_type(Path::new("a_lods.glb")), "model/gltf-binary");
        assert_eq!(
            content_type(Path::new("viewer/frond-three.js")),
            "text/javascript; charset=utf-8"
        );
    }

    #[test]
    fn only_local_host_names_are_answered() {
        let h = |s: &'static str| Some(header::HeaderValue::from_static(s));
        assert!(host_allowed(h("127.0.0.1:8417").as_ref(), 8417));
        assert!(host_allowed(h("localhost:8417").as_ref(), 8417));
        assert!(host_allowed(h("LOCALHOST").as_ref(), 8417));
        assert!(host_allowed(h("[::1]:8417").as_ref(), 8417));
        assert!(!host_allowed(h("127.0.0.1:9000").as_ref(), 8417));
        assert!(!host_allowed(h("evil.example:8417").as_ref(), 8417));
        assert!(!host_allowed(
            h("localhost.evil.example:8417").as_ref(),
            8417
        ));
        assert!(!host_allowed(None, 8417));
    }

    #[test]
    fn a_link_out_of_the_folder_is_never_opened() {
        let outside = tempfile::tempdir().unwrap();
        std::fs::write(outside.path().join("secret"), b"s").unwrap();
        let dir = tempfile::tempdir().unwrap();
        let root = dir.path().canonicalize().unwrap();
        std::fs::write(root.join("page.html"), b"p").unwrap();
        std::os::unix::fs::symlink(outside.path().join("secret"), root.join("link")).unwrap();
        std::os::unix::fs::symlink(outside.path(), root.join("dir")).unwrap();
        assert!(open_inside(&root, Path::new("page.html")).is_some());
        assert!(open_inside(&root, Path::new("link")).is_none());
        assert!(open_inside(&root, Path::new("dir/secret")).is_none());
    }
}
