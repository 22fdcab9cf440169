//! `frond view`'s web server: serves an output folder on localhost so its preview page's live
//! view can load the GLBs beside it (browsers refuse a page opened from disk any read of its
//! neighbours). Read-only, GET and HEAD only, files inside the folder only, one thread per
//! connection; nothing is cached (a rerun's files show on reload).
//!
//! Written on `std::net` rather than with a web framework: it serves static files to one local
//! browser, and an async runtime and HTTP stack would more than double frond's dependencies for
//! that.

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpListener, TcpStream};
use std::path::{Component, Path, PathBuf};
use std::time::Duration;

use anyhow::{Context, Result, bail};

/// A bound server over one folder.
pub struct ViewServer {
    listener: TcpListener,
    root: PathBuf,
    start: String,
}

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
        let listener = TcpListener::bind(("127.0.0.1", port)).with_context(|| {
            format!("cannot listen on 127.0.0.1:{port} (in use? --port 0 picks a free one)")
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
    pub fn serve(&self) -> Result<()> {
        for stream in self.listener.incoming() {
            let Ok(stream) = stream else { continue };
            let root = self.root.clone();
            std::thread::spawn(move || {
                if let Err(e) = handle(stream, &root) {
                    tracing::debug!("frond view: {e:#}");
                }
            });
        }
        Ok(())
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

/// Answers one request.
fn handle(stream: TcpStream, root: &Path) -> Result<()> {
    stream.set_read_timeout(Some(Duration::from_secs(10)))?;
    let mut reader = BufReader::new(stream.try_clone()?);
    let mut line = String::new();
    reader.by_ref().take(8192).read_line(&mut line)?;
    // Skip the headers (nothing in them changes the answer).
    let mut header = String::new();
    while reader.by_ref().take(8192).read_line(&mut header)? > 2 {
        header.clear();
    }
    let mut out = stream;
    let mut parts = line.split_whitespace();
    let (Some(method), Some(target)) = (parts.next(), parts.next()) else {
        return respond(&mut out, 400, "text/plain", b"bad request", true);
    };
    let head = method == "HEAD";
    if method != "GET" && !head {
        return respond(&mut out, 405, "text/plain", b"GET or HEAD only", true);
    }
    let path = target.split(['?', '#']).next().unwrap_or("/");
    let Some(rel) = decode_path(path) else {
        return respond(&mut out, 400, "text/plain", b"bad path", true);
    };
    if rel.as_os_str().is_empty() {
        let body = listing(root)?;
        return respond(
            &mut out,
            200,
            "text/html; charset=utf-8",
            body.as_bytes(),
            !head,
        );
    }
    let file = root.join(&rel);
    // A link inside the folder may point outside it: serve only what resolves inside.
    let inside = file
        .canonicalize()
        .is_ok_and(|f| f.starts_with(root) && f.is_file());
    if !inside {
        return respond(&mut out, 404, "text/plain", b"not found", !head);
    }
    let bytes = std::fs::read(&file)?;
    respond(&mut out, 200, content_type(&rel), &bytes, !head)
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
    let rel = PathBuf::from(text.trim_start_matches('/'));
    rel.components()
        .all(|c| matches!(c, Component::Normal(_)))
        .then_some(rel)
}

/// The listing `/` shows when the folder has no single page to open.
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
    Ok(frond_preview::index_page::index_page(
        &root.display().to_string(),
        &intro,
        &entries,
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

fn respond(
    out: &mut TcpStream,
    status: u16,
    kind: &str,
    body: &[u8],
    send_body: bool,
) -> Result<()> {
    let reason = match status {
        200 => "OK",
        400 => "Bad Request",
        404 => "Not Found",
        _ => "Method Not Allowed",
    };
    write!(
        out,
        "HTTP/1.1 {status} {reason}\r\nContent-Type: {kind}\r\nContent-Length: {}\r\n\
         Cache-Control: no-store\r\nConnection: close\r\n\r\n",
        body.len()
    )?;
    if send_body {
        out.write_all(body)?;
    }
    out.flush()?;
    Ok(())
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
}
