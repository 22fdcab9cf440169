//! The one gate every path frond writes, moves, deletes or serves passes.
//!
//! A path frond touches is always a name *relative to a folder the user chose* (the `-o`
//! folder, the folder `frond view` serves, the folder of `-o file.png`), never a path taken
//! whole from data. [`checked_path`] turns such a name into a path, refusing:
//!
//! - a name that is not plain: absolute, a drive prefix, empty, or holding `..` or `.`
//!   components (names come from journals, reports and manifests, which anyone can edit);
//! - a name that passes through a symbolic link (the last part included) which leads outside
//!   the folder, or which leads nowhere (writing through a dangling link would create its
//!   target, wherever that is). Links that stay inside the folder are followed.
//!
//! [`OutFolder`] performs every file-system change the application makes (create, write
//! atomically, rename, remove) through that check, so no other module calls `std::fs` to
//! change anything (`tests/out_folder_gate.rs` keeps it so). Reading a file to *serve* it
//! is checked after opening instead (see `view_server`), since a check before the open could
//! be raced by swapping a link.

use std::io::Write;
use std::path::{Component, Path, PathBuf};

/// Why a name was refused by [`checked_path`].
#[derive(Debug, thiserror::Error)]
pub enum PathRefusal {
    /// Absolute, empty, or holding `..`/`.`: not a plain name inside the folder.
    #[error(
        "'{name}' is not a plain relative name inside {folder} (absolute, empty, or with '..')"
    )]
    NotPlain {
        /// The name as given.
        name: String,
        /// The folder it should lie in.
        folder: String,
    },
    /// A part of the name is a symbolic link leading outside the folder (or nowhere).
    #[error("'{name}' goes through the link {link}, which leads outside {folder}")]
    LinkOut {
        /// The name as given.
        name: String,
        /// The link.
        link: String,
        /// The folder it should stay in.
        folder: String,
    },
    /// The folder itself cannot be resolved.
    #[error("{folder}: cannot resolve the folder ({source})")]
    Folder {
        /// The folder.
        folder: String,
        /// What the system said.
        source: std::io::Error,
    },
}

/// `root.join(name)` when `name` is a plain relative name whose existing parts below `root`
/// are no links leading outside `root` (see the module doc). `root` must exist.
pub fn checked_path(root: &Path, name: impl AsRef<Path>) -> Result<PathBuf, PathRefusal> {
    let name = name.as_ref();
    let shown = || name.to_string_lossy().into_owned();
    let folder = || root.display().to_string();
    let plain = !name.as_os_str().is_empty()
        && name.components().all(|c| matches!(c, Component::Normal(_)));
    if !plain {
        return Err(PathRefusal::NotPlain {
            name: shown(),
            folder: folder(),
        });
    }
    let canon_root = root.canonicalize().map_err(|source| PathRefusal::Folder {
        folder: folder(),
        source,
    })?;
    let mut at = root.to_path_buf();
    for part in name.components() {
        at.push(part);
        let Ok(meta) = std::fs::symlink_metadata(&at) else {
            // Nothing there yet: this part and those below it will be made by frond.
            break;
        };
        if meta.file_type().is_symlink() {
            let inside = at
                .canonicalize()
                .is_ok_and(|target| target.starts_with(&canon_root));
            if !inside {
                return Err(PathRefusal::LinkOut {
                    name: shown(),
                    link: at.display().to_string(),
                    folder: folder(),
                });
            }
        }
    }
    Ok(root.join(name))
}

/// A folder frond writes into; every change goes through [`checked_path`].
#[derive(Clone, Debug)]
pub struct OutFolder {
    root: PathBuf,
}

/// What the folder operations return: the refusal or the system's error, with the path named.
pub type FolderResult<T> = anyhow::Result<T>;

impl OutFolder {
    /// The folder `root` (as spelt: messages show it so), which need not exist yet.
    pub fn new(root: impl Into<PathBuf>) -> OutFolder {
        OutFolder { root: root.into() }
    }

    /// The folder of `-o file`: its parent (`.` for a bare name) and the file's name.
    pub fn of_file(file: &Path) -> anyhow::Result<(OutFolder, String)> {
        let name = file
            .file_name()
            .and_then(|n| n.to_str())
            .filter(|n| !n.is_empty())
            .ok_or_else(|| anyhow::anyhow!("{}: not a file name", file.display()))?;
        let dir = match file.parent() {
            Some(d) if !d.as_os_str().is_empty() => d,
            _ => Path::new("."),
        };
        Ok((OutFolder::new(dir), name.to_string()))
    }

    /// The folder as given.
    pub fn root(&self) -> &Path {
        &self.root
    }

    /// The checked path of `name` inside the folder.
    pub fn path(&self, name: impl AsRef<Path>) -> FolderResult<PathBuf> {
        Ok(checked_path(&self.root, name)?)
    }

    /// The subfolder `name` as a folder of its own (checked now; created by the writes).
    pub fn sub(&self, name: impl AsRef<Path>) -> FolderResult<OutFolder> {
        Ok(OutFolder::new(self.path(name)?))
    }

    /// Creates the folder itself and its missing parents (the user named it).
    pub fn create(&self) -> FolderResult<()> {
        std::fs::create_dir_all(&self.root).map_err(|e| {
            anyhow::Error::new(e)
                .context(format!("{}: cannot create the folder", self.root.display()))
        })
    }

    /// Creates subfolder `name`, which must not exist yet (Err if it does: a claim).
    pub fn create_dir(&self, name: impl AsRef<Path>) -> FolderResult<PathBuf> {
        let path = self.path(name)?;
        std::fs::create_dir(&path).map_err(|e| cannot(e, "create", &path))?;
        Ok(path)
    }

    /// Creates subfolder `name` and its missing parents inside the folder.
    pub fn create_dir_all(&self, name: impl AsRef<Path>) -> FolderResult<PathBuf> {
        self.create()?;
        let path = self.path(name)?;
        std::fs::create_dir_all(&path).map_err(|e| cannot(e, "create", &path))?;
        Ok(path)
    }

    /// Creates (or truncates) file `name` for writing, its folder made as needed. A link
    /// planted there after the check is not followed (`O_NOFOLLOW`: the open fails).
    pub fn create_file(&self, name: impl AsRef<Path>) -> FolderResult<std::fs::File> {
        use std::os::unix::fs::OpenOptionsExt;
        let path = self.path(&name)?;
        self.make_parent(name.as_ref())?;
        std::fs::OpenOptions::new()
            .write(true)
            .create(true)
            .truncate(true)
            .custom_flags(libc::O_NOFOLLOW)
            .open(&path)
            .map_err(|e| cannot(e, "create", &path))
    }

    /// Creates the folder `name` lies in, when it is a subfolder.
    fn make_parent(&self, name: &Path) -> FolderResult<()> {
        match name.parent() {
            Some(parent) if !parent.as_os_str().is_empty() => self.create_dir_all(parent).map(drop),
            _ => Ok(()),
        }
    }

    /// Writes `bytes` to `name` atomically (a temporary file beside it, synced, then renamed
    /// over it), so a failed run never leaves a partial file.
    pub fn write_atomic(&self, name: impl AsRef<Path>, bytes: &[u8]) -> FolderResult<()> {
        let name = name.as_ref();
        let path = self.path(name)?;
        let file = name
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        let tmp_name = name.with_file_name(format!(".{file}.tmp-{}", std::process::id()));
        let tmp = self.path(&tmp_name)?;
        self.make_parent(name)?;
        // A new file, never one found there (a link planted after the check is not followed):
        // a leftover of this pid's is removed first.
        let _ = std::fs::remove_file(&tmp);
        let mut f = std::fs::OpenOptions::new()
            .write(true)
            .create_new(true)
            .open(&tmp)
            .map_err(|e| cannot(e, "create", &tmp))?;
        let result = f
            .write_all(bytes)
            .and_then(|()| f.sync_all())
            .and_then(|()| std::fs::rename(&tmp, &path));
        if let Err(e) = result {
            let _ = std::fs::remove_file(&tmp);
            return Err(cannot(e, "write", &path));
        }
        Ok(())
    }

    /// Moves `from` to `to`, both inside the folder (one file system: atomic).
    pub fn rename(&self, from: impl AsRef<Path>, to: impl AsRef<Path>) -> FolderResult<()> {
        let (from, to) = (self.path(from)?, self.path(to)?);
        std::fs::rename(&from, &to).map_err(|e| cannot(e, "move into place", &to))
    }

    /// Removes file (or link) `name`.
    pub fn remove_file(&self, name: impl AsRef<Path>) -> FolderResult<()> {
        let path = self.path(name)?;
        std::fs::remove_file(&path).map_err(|e| cannot(e, "remove", &path))
    }

    /// Removes the empty folder `name` (a folder with anything in it stays: Err).
    pub fn remove_dir(&self, name: impl AsRef<Path>) -> FolderResult<()> {
        let path = self.path(name)?;
        std::fs::remove_dir(&path).map_err(|e| cannot(e, "remove", &path))
    }

    /// Removes `name` and everything in it (a link is removed, never followed).
    pub fn remove_dir_all(&self, name: impl AsRef<Path>) -> FolderResult<()> {
        let path = self.path(name)?;
        std::fs::remove_dir_all(&path).map_err(|e| cannot(e, "remove", &path))
    }

    /// Removes the folder itself when it is empty (a run that created it and failed).
    pub fn remove_self_if_empty(&self) -> bool {
        std::fs::remove_dir(&self.root).is_ok()
    }
}

/// The system's error with the operation and path named.
fn cannot(e: std::io::Error, what: &str, path: &Path) -> anyhow::Error {
    anyhow::Error::new(e).context(format!("{}: cannot {what}", path.display()))
}

/// Writes `bytes` to the file the user named (`-o tree.glb`, `-o frame.png`) atomically,
/// through [`OutFolder`] over its folder.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    let (folder, name) = OutFolder::of_file(path)?;
    folder.create()?;
    folder.write_atomic(&name, bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plain_names_pass_and_others_are_refused() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        assert_eq!(checked_path(d, "a/b.glb").unwrap(), d.join("a/b.glb"));
        for bad in ["", "/etc/passwd", "../x", "a/../../x", "./x", "a/.."] {
            let err = checked_path(d, bad).unwrap_err();
            assert!(matches!(err, PathRefusal::NotPlain { .. }), "{bad}: {err}");
        }
    }

    #[test]
    fn links_out_of_the_folder_are_refused_and_links_inside_followed() {
        let outside = tempfile::tempdir().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::create_dir(d.join("inner")).unwrap();
        std::os::unix::fs::symlink(outside.path(), d.join("out")).unwrap();
        std::os::unix::fs::symlink(d.join("inner"), d.join("alias")).unwrap();
        std::os::unix::fs::symlink("/nonexistent/x", d.join("dangling")).unwrap();
        std::os::unix::fs::symlink(outside.path().join("f"), d.join("file_out")).unwrap();
        for bad in ["out/x", "out", "dangling", "file_out"] {
            let err = checked_path(d, bad).unwrap_err();
            assert!(matches!(err, PathRefusal::LinkOut { .. }), "{bad}: {err}");
        }
        assert!(checked_path(d, "alias/x").is_ok());
        // A file is never created through a link, even one that stays inside.
        std::fs::write(d.join("inner/target"), b"kept").unwrap();
        std::os::unix::fs::symlink(d.join("inner/target"), d.join("inner/link")).unwrap();
        assert!(OutFolder::new(d).create_file("inner/link").is_err());
        assert_eq!(std::fs::read(d.join("inner/target")).unwrap(), b"kept");
        // Nothing was written through the refused link.
        let f = OutFolder::new(d);
        assert!(f.write_atomic("out/x", b"1").is_err());
        assert!(f.remove_dir_all("out").is_err());
        assert_eq!(std::fs::read_dir(outside.path()).unwrap().count(), 0);
    }

    #[test]
    fn atomic_writes_leave_the_file_or_nothing() {
        let dir = tempfile::tempdir().unwrap();
        let f = OutFolder::new(dir.path().join("new"));
        f.create().unwrap();
        f.write_atomic("sub/a.txt", b"one").unwrap();
        f.write_atomic("sub/a.txt", b"two").unwrap();
        assert_eq!(
            std::fs::read(dir.path().join("new/sub/a.txt")).unwrap(),
            b"two"
        );
        let names: Vec<_> = std::fs::read_dir(dir.path().join("new/sub"))
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names.len(), 1, "no temporary file left: {names:?}");
    }
}
