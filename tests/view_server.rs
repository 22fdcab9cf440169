//! `frond view` (`src/view_server.rs`) as an attacker and a crowd see it: nothing outside the
//! served folder is read, whatever links are swapped while it serves; slow and stalled clients
//! cost little and never keep a new client waiting past a second; a foreign `Host` is turned
//! away; answers carry no absolute path; running out of file descriptors does not stop it.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::os::unix::process::CommandExt;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// A running `frond view` (killed on drop).
struct Server {
    child: Child,
    addr: SocketAddr,
}

impl Drop for Server {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Server {
    /// Serves `folder`, under `limit` (a resource and its soft and hard value) if given.
    fn start(folder: &Path, limit: Option<(libc::__rlimit_resource_t, u64)>) -> Server {
        let mut c = Command::new(env!("CARGO_BIN_EXE_frond"));
        c.args(["view", folder.to_str().unwrap(), "--port", "0", "--no-open"])
            .stdout(Stdio::piped())
            .stderr(Stdio::null());
        if let Some((resource, n)) = limit {
            // SAFETY: setrlimit is async-signal-safe and touches only the child.
            unsafe {
                c.pre_exec(move || {
                    let lim = libc::rlimit {
                        rlim_cur: n,
                        rlim_max: n,
                    };
                    if libc::setrlimit(resource, &lim) != 0 {
                        return Err(std::io::Error::last_os_error());
                    }
                    Ok(())
                });
            }
        }
        let mut child = c.spawn().expect("frond view starts");
        let mut stdout = child.stdout.take().expect("stdout");
        let mut line = Vec::new();
        let mut byte = [0u8; 1];
        while stdout.read(&mut byte).expect("reads") == 1 && byte[0] != b'\n' {
            line.push(byte[0]);
        }
        let url = String::from_utf8(line).expect("URL");
        let addr = url
            .trim_start_matches("http://")
            .split('/')
            .next()
            .unwrap()
            .parse()
            .expect("address");
        Server { child, addr }
    }

    /// Still running.
    fn alive(&mut self) -> bool {
        self.child.try_wait().expect("wait").is_none()
    }

    /// The process's peak resident memory so far, bytes.
    fn peak(&self) -> u64 {
        let status = std::fs::read_to_string(format!("/proc/{}/status", self.child.id())).unwrap();
        let line = status.lines().find(|l| l.starts_with("VmHWM:")).unwrap();
        line.split_whitespace()
            .nth(1)
            .unwrap()
            .parse::<u64>()
            .unwrap()
            * 1024
    }

    /// GET `path` with `host` as the Host: (status, body), or None when the connection fails.
    fn get_as(&self, path: &str, host: &str) -> Option<(u16, Vec<u8>)> {
        let mut s = TcpStream::connect_timeout(&self.addr, Duration::from_secs(5)).ok()?;
        s.set_read_timeout(Some(Duration::from_secs(10))).ok()?;
        write!(
            s,
            "GET {path} HTTP/1.1\r\nHost: {host}\r\nConnection: close\r\n\r\n"
        )
        .ok()?;
        let mut raw = Vec::new();
        s.read_to_end(&mut raw).ok()?;
        let end = raw.windows(4).position(|w| w == b"\r\n\r\n")?;
        let head = String::from_utf8_lossy(&raw[..end]).into_owned();
        let status = head.split_whitespace().nth(1)?.parse().ok()?;
        Some((status, raw[end + 4..].to_vec()))
    }

    fn get(&self, path: &str) -> Option<(u16, Vec<u8>)> {
        self.get_as(path, &self.addr.to_string())
    }
}

/// A served folder with a page, a secret outside it, and `link` pointing at the page.
fn site() -> (tempfile::TempDir, std::path::PathBuf, std::path::PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let served = dir.path().join("served");
    std::fs::create_dir_all(&served).unwrap();
    std::fs::write(served.join("tree_preview.html"), b"inside").unwrap();
    let secret = dir.path().join("secret.txt");
    std::fs::write(&secret, b"SECRET").unwrap();
    (dir, served, secret)
}

#[test]
fn a_link_swapped_while_serving_never_serves_outside_the_folder() {
    let (_dir, served, secret) = site();
    let server = Server::start(&served, None);
    let link = served.join("link.html");
    let inside = served.join("tree_preview.html");
    std::os::unix::fs::symlink(&inside, &link).unwrap();
    // Swap the link between the page and the secret as fast as possible (rename over it,
    // atomically), while requests for it keep coming.
    let stop = std::sync::Arc::new(std::sync::atomic::AtomicBool::new(false));
    let swapper = {
        let (stop, link, served, secret) =
            (stop.clone(), link.clone(), served.clone(), secret.clone());
        std::thread::spawn(move || {
            let mut k = 0u64;
            while !stop.load(std::sync::atomic::Ordering::Relaxed) {
                let tmp = served.join(format!(".swap{}", k % 2));
                let target = if k.is_multiple_of(2) {
                    &secret
                } else {
                    &inside
                };
                let _ = std::fs::remove_file(&tmp);
                std::os::unix::fs::symlink(target, &tmp).unwrap();
                std::fs::rename(&tmp, &link).unwrap();
                k += 1;
            }
            k
        })
    };
    let (mut served_inside, mut leaked) = (0, 0);
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(4) {
        if let Some((status, body)) = server.get("/link.html") {
            if body == b"SECRET" {
                leaked += 1;
            } else if status == 200 {
                served_inside += 1;
            }
        }
    }
    stop.store(true, std::sync::atomic::Ordering::Relaxed);
    let swaps = swapper.join().unwrap();
    assert_eq!(leaked, 0, "bodies from outside the folder");
    assert!(
        swaps > 1000 && served_inside > 10,
        "{swaps} swaps, {served_inside} served"
    );
    // Links to the outside, to a folder outside, and paths out are refused plainly.
    std::os::unix::fs::symlink(secret.parent().unwrap(), served.join("up")).unwrap();
    for path in ["/up/secret.txt", "/../secret.txt", "/%2e%2e/secret.txt"] {
        let (status, body) = server.get(path).expect("answered");
        assert!(status == 404 || status == 400, "{path}: {status}");
        assert_ne!(body, b"SECRET");
    }
}

#[test]
fn slow_clients_never_keep_a_new_one_waiting() {
    let (_dir, served, _) = site();
    let big = vec![7u8; 50 << 20];
    std::fs::write(served.join("big.glb"), &big).unwrap();
    let mut server = Server::start(&served, None);
    // 500 slow-loris clients: each sends part of a request line and then nothing.
    let mut slow = Vec::new();
    for _ in 0..500 {
        let mut s = TcpStream::connect(server.addr).expect("connects");
        s.write_all(b"GET /tree_preview.html HTTP/1.1\r\nHost: 127.0.0.1\r\n")
            .unwrap();
        slow.push(s);
    }
    // 20 clients ask for the 50 MB file and never read it.
    let mut stalled = Vec::new();
    for _ in 0..20 {
        let mut s = TcpStream::connect(server.addr).expect("connects");
        write!(s, "GET /big.glb HTTP/1.1\r\nHost: {}\r\n\r\n", server.addr).unwrap();
        stalled.push(s);
    }
    std::thread::sleep(Duration::from_millis(500));
    let t = Instant::now();
    let (status, body) = server
        .get("/tree_preview.html")
        .expect("a new client is served");
    assert_eq!((status, body.as_slice()), (200, b"inside".as_slice()));
    assert!(t.elapsed() < Duration::from_secs(1), "{:?}", t.elapsed());
    assert!(server.alive());
    // Files are streamed: 20 stalled readers of 50 MB do not hold 1 GB.
    let peak = server.peak();
    assert!(peak < 150 << 20, "server peak {} MB", peak >> 20);
    // And a whole file still arrives intact.
    let (status, body) = server.get("/big.glb").expect("served");
    assert_eq!(status, 200);
    assert!(body == big, "{} bytes", body.len());
    drop(slow);
    drop(stalled);
}

#[test]
fn only_local_host_names_are_answered_and_no_absolute_path_is_shown() {
    let (_dir, served, _) = site();
    std::fs::write(served.join("other_preview.html"), b"other").unwrap();
    let server = Server::start(&served, None);
    let port = server.addr.port();
    // A DNS-rebinding page reaches 127.0.0.1 with its own name as the Host.
    let (status, body) = server
        .get_as("/tree_preview.html", &format!("attacker.example:{port}"))
        .expect("answered");
    assert_eq!(status, 421);
    assert_ne!(body, b"inside");
    for host in [format!("localhost:{port}"), format!("127.0.0.1:{port}")] {
        let (status, _) = server
            .get_as("/tree_preview.html", &host)
            .expect("answered");
        assert_eq!(status, 200, "{host}");
    }
    // Two pages: `/` lists them, titled with the folder's name, never its absolute path.
    let (status, listing) = server.get("/").expect("listing");
    let listing = String::from_utf8(listing).unwrap();
    assert_eq!(status, 200);
    assert!(listing.contains("tree_preview.html"), "{listing}");
    // A named pipe in the folder: refused as not a file, without waiting for a writer.
    let fifo = served.join("pipe.glb");
    let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
    let t = Instant::now();
    assert_eq!(server.get("/pipe.glb").map(|a| a.0), Some(404));
    assert!(t.elapsed() < Duration::from_secs(2));
    assert_eq!(server.get("/tree_preview.html").map(|a| a.0), Some(200));
    let abs = served.canonicalize().unwrap();
    assert!(!listing.contains(abs.to_str().unwrap()), "{listing}");
    assert!(!listing.contains(served.parent().unwrap().to_str().unwrap()));
}

/// Opens `n` connections that each send part of a request and stall; checks the server lives
/// through them and serves again once they are gone.
#[track_caller]
fn survives_stalled_crowd(server: &mut Server, n: usize) {
    let mut held = Vec::new();
    for _ in 0..n {
        if let Ok(mut s) = TcpStream::connect_timeout(&server.addr, Duration::from_secs(2)) {
            let _ = s.write_all(b"GET / HTTP/1.1\r\n");
            held.push(s);
        }
    }
    std::thread::sleep(Duration::from_millis(500));
    assert!(server.alive(), "the server exited");
    drop(held);
    let t = Instant::now();
    let mut answer = None;
    while answer.is_none() && t.elapsed() < Duration::from_secs(15) {
        answer = server.get("/tree_preview.html");
    }
    assert_eq!(answer.map(|a| a.0), Some(200));
    assert!(server.alive());
}

#[test]
fn running_out_of_threads_or_descriptors_does_not_stop_the_server() {
    let (_dir, served, _) = site();
    // 512 MiB of address space: a thread per connection ran out at 38 clients, and the
    // failed spawn panicked the server out of its accept loop.
    let mut server = Server::start(&served, Some((libc::RLIMIT_AS, 512 << 20)));
    survives_stalled_crowd(&mut server, 400);
    drop(server);
    // More connections than the server may hold descriptors for.
    let mut server = Server::start(&served, Some((libc::RLIMIT_NOFILE, 48)));
    survives_stalled_crowd(&mut server, 120);
}
