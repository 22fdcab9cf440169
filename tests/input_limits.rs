//! Nothing a user feeds frond makes it read outside the input's folder, hang, or take unbounded
//! memory (`scene/src/input_file.rs`): FIFOs, devices and `../` URIs through `inspect`, `lod`
//! and `batch`; decoded-texture and input-size budgets with errors that name the limit and the
//! option that raises it.

use crate::common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use common::gltf_cases::*;
use common::hostile::png_header_only;
use common::*;
use serde_json::{Value, json};

/// Runs frond with `args`, killing it if it runs past `limit` (a hang fails the test instead of
/// the suite).
fn frond_within(args: &[&str], limit: Duration) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_frond"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("frond runs");
    let start = Instant::now();
    while child.try_wait().expect("wait").is_none() {
        if start.elapsed() > limit {
            let _ = child.kill();
            let out = child.wait_with_output().expect("output");
            panic!(
                "frond {args:?} still running after {limit:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().expect("output")
}

fn mkfifo(path: &Path) {
    let c = std::ffi::CString::new(path.to_str().expect("utf-8")).expect("path");
    // SAFETY: mkfifo with a valid NUL-terminated path.
    assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0, "mkfifo");
}

/// A `.gltf` in `dir/tree/` whose buffer URI is `uri` (`tri.bin` beside it is valid).
fn gltf_with_buffer_uri(dir: &Path, uri: &str) -> PathBuf {
    let mut doc = triangle_gltf();
    doc["buffers"][0]["uri"] = json!(uri);
    write_case(dir, "tree", &doc, &triangle_bin(GOOD, [0, 1, 2]))
}

/// Asserts a one-line error naming `path` and saying `needle`, exit code 1.
#[track_caller]
fn refused(out: &Output, path: &Path, needle: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "exit code; stderr: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(
        err.contains(&path.display().to_string()),
        "names the file: {err}"
    );
    assert!(err.contains(needle), "says '{needle}': {err}");
}

const QUICK: Duration = Duration::from_secs(60);

#[test]
fn a_fifo_or_a_device_as_the_input_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("tree.glb");
    mkfifo(&fifo);
    let p = fifo.to_str().unwrap();
    refused(
        &frond_within(&["inspect", p], QUICK),
        &fifo,
        "named pipe (FIFO)",
    );
    let out = dir.path().join("out");
    let o = out.to_str().unwrap();
    refused(&frond_within(&["lod", p, "-o", o], QUICK), &fifo, "FIFO");
    assert!(!out.exists(), "no output folder");
    let zero = Path::new("/dev/zero");
    refused(
        &frond_within(&["inspect", "/dev/zero"], QUICK),
        zero,
        "character device",
    );
}

#[test]
fn buffer_uris_that_are_fifos_devices_or_outside_the_folder_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    type Setup = fn(&Path);
    let cases: [(&str, &str, Setup); 5] = [
        ("pipe.bin", "FIFO", |d| mkfifo(&d.join("tree/pipe.bin"))),
        ("zero.bin", "symbolic link", |d| {
            std::os::unix::fs::symlink("/dev/zero", d.join("tree/zero.bin")).unwrap()
        }),
        ("/dev/zero", "outside the input folder", |_| {}),
        (
            "../../../../../../etc/passwd",
            "outside the input folder",
            |_| {},
        ),
        ("file:///etc/passwd", "outside the input folder", |_| {}),
    ];
    for (uri, needle, setup) in cases {
        let case = dir.path().join(uri.replace(['/', ':', '.'], "_"));
        std::fs::create_dir_all(&case).unwrap();
        let path = gltf_with_buffer_uri(&case, uri);
        setup(&case);
        let p = path.to_str().unwrap();
        let out = frond_within(&["inspect", p], QUICK);
        refused(&out, &path, needle);
        assert!(
            String::from_utf8_lossy(&out.stderr).contains(uri),
            "names the URI"
        );
    }
    // `sub/../tri.bin` is inside the folder: read.
    let inside = dir.path().join("inside");
    let path = gltf_with_buffer_uri(&inside, "sub/../tri.bin");
    std::fs::create_dir_all(inside.join("tree/sub")).unwrap();
    let out = frond_within(&["inspect", "--json", path.to_str().unwrap()], QUICK);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn batch_never_opens_what_the_import_refuses_nor_hangs_on_it() {
    let dir = tempfile::tempdir().unwrap();
    let library = dir.path().join("library");
    // A FIFO inside the tree's folder, one outside it, and /dev/zero through a symlink.
    gltf_with_buffer_uri(&library.join("a"), "pipe.bin");
    mkfifo(&library.join("a/tree/pipe.bin"));
    let outside = gltf_with_buffer_uri(&library.join("b"), "../../../outside.bin");
    std::fs::write(dir.path().join("outside.bin"), b"secret").unwrap();
    gltf_with_buffer_uri(&library.join("c"), "zero.bin");
    std::os::unix::fs::symlink("/dev/zero", library.join("c/tree/zero.bin")).unwrap();
    let out = dir.path().join("out");
    let run = frond_within(
        &[
            "batch",
            library.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--jobs",
            "1",
            "--timeout",
            "600",
        ],
        Duration::from_secs(300),
    );
    assert_eq!(run.status.code(), Some(1));
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(
        err.contains("3 trees: 0 built, 0 up to date, 3 failed"),
        "{err}"
    );
    let summary: frond_app::batch::summary::BatchSummary = read_json(&out.join("summary.json"));
    for (t, needle) in
        summary
            .trees
            .iter()
            .zip(["FIFO", "outside the input folder", "symbolic link"])
    {
        let reason = t.reason.as_deref().unwrap_or_default();
        assert!(reason.contains(needle), "{t:?}");
    }
    // The hash of the tree whose URI leaves the folder does not depend on what is out there.
    let hash = |path: &Path| {
        frond_app::batch::inputs::input_hash(path, &frond_scene::InputLimits::default()).unwrap()
    };
    let before = hash(&outside);
    std::fs::write(dir.path().join("outside.bin"), b"other secret").unwrap();
    assert_eq!(hash(&outside), before);
}

/// The triangle with `images` textured materials, one image each (PNG files beside it).
fn textured(dir: &Path, images: &[Vec<u8>]) -> PathBuf {
    let mut doc = triangle_gltf();
    let n = images.len();
    doc["images"] = json!(
        (0..n)
            .map(|i| json!({ "uri": format!("map{i}.png") }))
            .collect::<Vec<_>>()
    );
    doc["textures"] = json!((0..n).map(|i| json!({ "source": i })).collect::<Vec<_>>());
    doc["materials"] = json!(
        (0..n)
            .map(|i| json!({ "pbrMetallicRoughness": { "baseColorTexture": { "index": i } } }))
            .collect::<Vec<_>>()
    );
    // Every material used: one primitive each.
    let prims: Vec<Value> = (0..n)
        .map(|i| json!({ "attributes": { "POSITION": 0 }, "indices": 1, "material": i }))
        .collect();
    doc["meshes"][0]["primitives"] = json!(prims);
    let path = write_case(dir, "tree", &doc, &triangle_bin(GOOD, [0, 1, 2]));
    for (i, png) in images.iter().enumerate() {
        std::fs::write(dir.join("tree").join(format!("map{i}.png")), png).unwrap();
    }
    path
}

#[test]
fn texture_bombs_are_refused_from_their_headers() {
    let dir = tempfile::tempdir().unwrap();
    // One 11500² map: 529 MB decoded, over the 384 MiB default.
    let one = textured(&dir.path().join("one"), &[png_header_only(11_500, 11_500)]);
    assert!(
        std::fs::metadata(one.with_file_name("map0.png"))
            .unwrap()
            .len()
            < 200
    );
    let p = one.to_str().unwrap();
    let out = frond_within(&["inspect", p], QUICK);
    refused(&out, &one, "texture memory limit of 384 MiB");
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-texture-memory"));
    // Four 8192² maps: each under any per-image cap, 1 GiB together.
    let four = textured(
        &dir.path().join("four"),
        &vec![png_header_only(8192, 8192); 4],
    );
    let out = frond_within(&["inspect", four.to_str().unwrap()], QUICK);
    refused(&out, &four, "its 4 images decode to 1 GiB");
    // Raising the limit lets the reader go on to decode the image (which is then found broken).
    let out = frond_within(&["inspect", p, "--max-texture-memory", "1G"], QUICK);
    refused(&out, &one, "cannot decode");
    // Six 4096² maps fit the default (a real tree with several 4K maps).
    let four_k = image::RgbaImage::new(4096, 4096);
    let mut png = Vec::new();
    image::DynamicImage::ImageRgba8(four_k)
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let six = textured(&dir.path().join("six"), &vec![png; 6]);
    let out = frond_within(&["inspect", "--json", six.to_str().unwrap()], QUICK);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn the_input_size_limit_names_its_option() {
    let sample = root().join("samples/sapling.glb");
    let out = frond_within(
        &[
            "inspect",
            sample.to_str().unwrap(),
            "--max-input-size",
            "100K",
        ],
        QUICK,
    );
    refused(&out, &sample, "over the input size limit of 100 KiB");
    assert!(String::from_utf8_lossy(&out.stderr).contains("--max-input-size"));
    // External buffers count towards it too.
    let dir = tempfile::tempdir().unwrap();
    let path = gltf_with_buffer_uri(dir.path(), "tri.bin");
    let size = std::fs::metadata(&path).unwrap().len();
    let limit = format!("{}", size + 10);
    let out = frond_within(
        &[
            "inspect",
            path.to_str().unwrap(),
            "--max-input-size",
            &limit,
        ],
        QUICK,
    );
    refused(&out, &path, "external buffers add up to");
}

#[test]
fn a_closed_output_pipe_ends_frond_quietly() {
    use std::os::fd::FromRawFd;
    use std::os::unix::process::ExitStatusExt;
    let mut fds = [0i32; 2];
    // SAFETY: pipe fills two valid descriptors; we own both.
    assert_eq!(unsafe { libc::pipe(fds.as_mut_ptr()) }, 0);
    // SAFETY: fds[0] is a descriptor we own; dropping the File closes it (nobody reads).
    drop(unsafe { std::fs::File::from_raw_fd(fds[0]) });
    // SAFETY: fds[1] is a descriptor we own, handed to the child as its stdout.
    let write_end = unsafe { std::fs::File::from_raw_fd(fds[1]) };
    let sample = root().join("samples/sapling.glb");
    let out = Command::new(env!("CARGO_BIN_EXE_frond"))
        .args(["inspect", "--json"])
        .arg(&sample)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdout(write_end)
        .stderr(Stdio::piped())
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(out.status.signal(), Some(libc::SIGPIPE), "{err}");
}

#[test]
fn what_the_fuzzer_found_gets_clean_errors_in_bounded_memory() {
    // fuzz/regressions: a GLB header declaring 1 byte (an overflow panic inside the gltf crate
    // in debug builds), and two small files that declare tens of millions of vertices (an
    // accessor without a bufferView; one mesh instanced on hundreds of nodes).
    let dir = root().join("fuzz/regressions");
    for (file, needle) in [
        (
            "glb_header_length_below_12.glb",
            "truncated or malformed GLB",
        ),
        (
            "oom_viewless_position_16m.gltf",
            "over the vertex limit of 8000000",
        ),
        ("oom_instancing_amplification.gltf", "--max-vertices"),
    ] {
        let path = dir.join(file);
        let out = frond_within(&["inspect", path.to_str().unwrap()], QUICK);
        refused(&out, &path, needle);
        assert_eq!(
            String::from_utf8_lossy(&out.stderr).trim().lines().count(),
            1
        );
    }
}
