//! The one place that opens a user's input files: the tree itself and every file its glTF
//! names (external buffers and images). Every reader of input files (the importer, `frond
//! batch`'s input hashing) goes through here so they share one set of rules:
//!
//! - **regular files only**: a FIFO, a device such as `/dev/zero`, a socket or a folder is
//!   refused before a byte is read. The file is opened non-blocking (opening a FIFO for reading
//!   would otherwise wait for a writer forever) and checked with `fstat` on the open handle, so
//!   a file swapped for a FIFO between a check and the open cannot slip through;
//! - **size-capped**: a file over [`InputLimits::max_input_bytes`] is refused from its size,
//!   and the read itself stops one byte past the cap, so a file that grows while being read
//!   cannot take unbounded memory;
//! - **inside the input's folder**: an external URI is decoded, normalised lexically (`sub/../x`
//!   is `x`, inside) and then resolved through symlinks; the result must be a file below the
//!   folder of the `.gltf` that names it. Absolute paths, any URI scheme (`file:`, `http:`, a
//!   drive letter) and anything that leaves the folder are refused.

use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// How much reading one input may cost. Each limit can be raised by the caller; the error that
/// refuses an input names the limit it is over ("the input size limit", "the texture memory
/// limit", "the vertex limit", "the animation key limit").
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct InputLimits {
    /// Bytes of input files read for one tree: the file itself plus every external buffer and
    /// every external image a material uses (all passed through, decoded or not). Default
    /// 1 GiB: several times the 1 M-foliage-triangle `xlarge` sample preset, and a GLB cannot
    /// exceed 4 GiB anyway.
    pub max_input_bytes: u64,
    /// Decoded texture memory of one tree, counted as 4 bytes (RGBA8) per texel of every image
    /// a material map uses (any slot, any format: frond decodes base-colour and normal maps on
    /// import and may decode any map to write it smaller), each image once, summed from the
    /// headers before any is decoded. Default 384 MiB: six 4096²
    /// maps, such as colour, normal and occlusion-roughness-metal on bark and on leaves.
    pub max_texture_bytes: u64,
    /// Vertices of all mesh instances together (a mesh used by n nodes counts n times), checked
    /// from the accessors' declared counts before decoding. Default 8 M: a few times the
    /// `xlarge` sample's vertices, and it keeps the importer's geometry under half a GB however
    /// the file amplifies it (instancing, accessors without a bufferView).
    pub max_vertices: u64,
    /// Animation keys of all clips together, counted from the time accessors' declared counts
    /// before any is read: each channel counts its keys, and at least [`MIN_CHANNEL_KEYS`]
    /// (frond evaluates a channel at that many poses, and writes it into every LOD file however
    /// short it is); each clip at least [`MIN_CLIP_KEYS`] (each is evaluated and written on its
    /// own). Default 2 Mi: 28 clips of a 600-bone tree keyed at
    /// 30 fps for 4 s; the keys are held and written once per LOD file, so this keeps them to a
    /// few hundred MB however many clips or channels share one accessor.
    pub max_animation_keys: u64,
}

/// The least a channel counts towards [`InputLimits::max_animation_keys`].
pub const MIN_CHANNEL_KEYS: u64 = 64;
/// The least a clip counts towards [`InputLimits::max_animation_keys`].
pub const MIN_CLIP_KEYS: u64 = 1024;

/// Default of [`InputLimits::max_input_bytes`].
pub const DEFAULT_MAX_INPUT_BYTES: u64 = 1 << 30;
/// Default of [`InputLimits::max_texture_bytes`].
pub const DEFAULT_MAX_TEXTURE_BYTES: u64 = 384 << 20;
/// Default of [`InputLimits::max_vertices`].
pub const DEFAULT_MAX_VERTICES: u64 = 8_000_000;
/// Default of [`InputLimits::max_animation_keys`].
pub const DEFAULT_MAX_ANIMATION_KEYS: u64 = 1 << 21;
impl Default for InputLimits {
    fn default() -> Self {
        InputLimits {
            max_input_bytes: DEFAULT_MAX_INPUT_BYTES,
            max_texture_bytes: DEFAULT_MAX_TEXTURE_BYTES,
            max_vertices: DEFAULT_MAX_VERTICES,
            max_animation_keys: DEFAULT_MAX_ANIMATION_KEYS,
        }
    }
}

/// Formats a byte count the way the limits' options take it (`1 GiB`, `384 MiB`, `947 KiB`).
pub fn human_bytes(bytes: u64) -> String {
    const UNITS: [(&str, u64); 3] = [("GiB", 1 << 30), ("MiB", 1 << 20), ("KiB", 1 << 10)];
    for (unit, size) in UNITS {
        if bytes >= size {
            let v = bytes as f64 / size as f64;
            return if v.fract() == 0.0 {
                format!("{v:.0} {unit}")
            } else {
                format!("{v:.1} {unit}")
            };
        }
    }
    format!("{bytes} bytes")
}

/// What kind of file system entry a refused path is, in words.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a named pipe (FIFO)"
    } else if t.is_char_device() {
        "a character device"
    } else if t.is_block_device() {
        "a block device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Why an input file could not be read; the caller adds the file's name.
#[derive(Debug)]
pub enum ReadRefusal {
    /// The operating system refused (missing file, permissions, …).
    Io(std::io::Error),
    /// Not a regular file (FIFO, device, socket, folder).
    NotRegular(&'static str),
    /// Larger than the cap.
    TooLarge {
        /// The file's size (or a lower bound, for a file that grew while read).
        size: u64,
        /// The cap in force.
        limit: u64,
    },
}

impl std::fmt::Display for ReadRefusal {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ReadRefusal::Io(e) => write!(f, "cannot be read ({e})"),
            ReadRefusal::NotRegular(kind) => {
                write!(
                    f,
                    "is {kind}, not a regular file (only regular files are read)"
                )
            }
            ReadRefusal::TooLarge { size, limit } => write!(
                f,
                "is {} ({size} bytes), over the input size limit of {} (raise the input size limit to read it)",
                human_bytes(*size),
                human_bytes(*limit)
            ),
        }
    }
}

/// Reads a regular file of at most `limit` bytes (see the module doc for the rules).
pub fn read_regular_file(path: &Path, limit: u64) -> Result<Vec<u8>, ReadRefusal> {
    use std::os::unix::fs::OpenOptionsExt;
    let file = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(libc::O_NONBLOCK | libc::O_NOCTTY)
        .open(path)
        .map_err(ReadRefusal::Io)?;
    let meta = file.metadata().map_err(ReadRefusal::Io)?;
    if !meta.is_file() {
        return Err(ReadRefusal::NotRegular(kind_of(&meta)));
    }
    if meta.len() > limit {
        return Err(ReadRefusal::TooLarge {
            size: meta.len(),
            limit,
        });
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(ReadRefusal::Io)?;
    if bytes.len() as u64 > limit {
        return Err(ReadRefusal::TooLarge {
            size: bytes.len() as u64,
            limit,
        });
    }
    Ok(bytes)
}

/// Where an external URI of a glTF in `dir` points, if it is a file inside `dir`: the path to
/// open (symlinks resolved). `Err` says why not, in words that follow "external URI 'x' ".
pub fn resolve_uri(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    // A bare file name's parent is the empty path: the current folder.
    let dir = if dir.as_os_str().is_empty() {
        Path::new(".")
    } else {
        dir
    };
    let rel = percent_decode(uri);
    if has_scheme(&rel) || rel.starts_with('/') || rel.starts_with('\\') {
        return Err(
            "is outside the input folder (only relative paths inside it are read)".to_string(),
        );
    }
    // Lexical normalisation first: `sub/../leaf.png` names a file inside the folder.
    let mut inside = PathBuf::new();
    for c in Path::new(&rel).components() {
        match c {
            Component::Normal(part) => inside.push(part),
            Component::CurDir => {}
            Component::ParentDir => {
                if !inside.pop() {
                    return Err("is outside the input folder".to_string());
                }
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err("is outside the input folder".to_string());
            }
        }
    }
    if inside.as_os_str().is_empty() {
        return Err("names the input folder itself, not a file".to_string());
    }
    // Then the file system's view: a symlink (or a `..` after one) may still leave the folder.
    // The lexical path is what the author meant; the canonical one is what would be opened.
    let full = dir.join(&rel);
    let canon_dir = dir
        .canonicalize()
        .map_err(|e| format!("cannot be resolved: the input folder is unreadable ({e})"))?;
    let canon = match full.canonicalize() {
        Ok(c) => c,
        // Missing files are reported by the read, with the OS's words.
        Err(_) => return Ok(canon_dir.join(inside)),
    };
    if !canon.starts_with(&canon_dir) {
        return Err("resolves outside the input folder (through a symbolic link)".to_string());
    }
    Ok(canon)
}

/// `scheme:` at the start of a URI (RFC 3986: a letter, then letters, digits, `+`, `-`, `.`).
/// A Windows drive letter (`C:`) counts too, which is what we want: it is not relative.
fn has_scheme(uri: &str) -> bool {
    let Some((scheme, _)) = uri.split_once(':') else {
        return false;
    };
    let mut chars = scheme.chars();
    chars.next().is_some_and(|c| c.is_ascii_alphabetic())
        && chars.all(|c| c.is_ascii_alphanumeric() || matches!(c, '+' | '-' | '.'))
}

/// Decodes `%XX` escapes in a relative URI.
fn percent_decode(s: &str) -> String {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%'
            && i + 2 < bytes.len()
            && let Ok(v) = u8::from_str_radix(
                std::str::from_utf8(&bytes[i + 1..i + 3]).unwrap_or("zz"),
                16,
            )
        {
            out.push(v);
            i += 3;
            continue;
        }
        out.push(bytes[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uris_inside_and_outside() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir_all(d.join("sub")).unwrap();
        std::fs::write(d.join("leaf.png"), b"x").unwrap();
        let canon = d.canonicalize().unwrap();
        assert_eq!(
            resolve_uri(d, "sub/../leaf.png").unwrap(),
            canon.join("leaf.png")
        );
        assert_eq!(
            resolve_uri(d, "./leaf.png").unwrap(),
            canon.join("leaf.png")
        );
        assert_eq!(
            resolve_uri(d, "leaf%2Epng").unwrap(),
            canon.join("leaf.png")
        );
        for bad in [
            "../leaf.png",
            "sub/../../leaf.png",
            "/etc/passwd",
            "file:leaf.png",
            "file:///etc/passwd",
            "http://example.invalid/x.bin",
            "C:leaf.png",
            "\\\\server\\share",
            ".",
        ] {
            assert!(resolve_uri(d, bad).is_err(), "{bad} refused");
        }
        std::os::unix::fs::symlink("/etc", d.join("out")).unwrap();
        let err = resolve_uri(d, "out/passwd").unwrap_err();
        assert!(err.contains("symbolic link"), "{err}");
        // A symlink that stays inside is fine.
        std::os::unix::fs::symlink(d.join("leaf.png"), d.join("alias.png")).unwrap();
        assert_eq!(resolve_uri(d, "alias.png").unwrap(), canon.join("leaf.png"));
    }

    #[test]
    fn only_regular_files_within_the_cap() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("a.bin");
        std::fs::write(&f, [7u8; 100]).unwrap();
        assert_eq!(read_regular_file(&f, 100).unwrap().len(), 100);
        let err = read_regular_file(&f, 99).unwrap_err().to_string();
        assert!(
            err.contains("100 bytes") && err.contains("raise the input size limit"),
            "{err}"
        );
        let err = read_regular_file(dir.path(), 1 << 20)
            .unwrap_err()
            .to_string();
        assert!(err.contains("a folder"), "{err}");
        let err = read_regular_file(Path::new("/dev/zero"), 1 << 20)
            .unwrap_err()
            .to_string();
        assert!(err.contains("character device"), "{err}");
        let fifo = dir.path().join("pipe");
        let c = std::ffi::CString::new(fifo.to_str().unwrap()).unwrap();
        // SAFETY: mkfifo with a valid NUL-terminated path.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let err = read_regular_file(&fifo, 1 << 20).unwrap_err().to_string();
        assert!(err.contains("FIFO"), "{err}");
    }

    #[test]
    fn sizes_in_words() {
        assert_eq!(human_bytes(1 << 30), "1 GiB");
        assert_eq!(human_bytes(384 << 20), "384 MiB");
        assert_eq!(human_bytes(1536), "1.5 KiB");
        assert_eq!(human_bytes(12), "12 bytes");
    }
}
