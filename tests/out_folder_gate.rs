//! Every path frond writes, moves or deletes passes one checked function
//! (`src/out_folder.rs`): no other module of the application (`src/`) or of the pipeline's
//! libraries calls the standard library to change the file system. Read as text, tests
//! (`#[cfg(test)]` modules) aside.

use std::path::Path;

/// Calls that change the file system.
const CHANGES: &[&str] = &[
    "fs::write(",
    "fs::rename(",
    "fs::remove_file(",
    "fs::remove_dir(",
    "fs::remove_dir_all(",
    "fs::create_dir(",
    "fs::create_dir_all(",
    "fs::copy(",
    "fs::hard_link(",
    "fs::set_permissions(",
    "File::create(",
    ".write(true)",
    ".create(true)",
    ".append(true)",
    "symlink(",
];

fn rust_files(dir: &Path, out: &mut Vec<std::path::PathBuf>) {
    for e in std::fs::read_dir(dir).expect("list") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn only_the_gate_changes_the_file_system() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for dir in [
        "src",
        "scene/src",
        "spectral/src",
        "skeleton/src",
        "render/src",
        "billboard/src",
        "lod/src",
        "export/src",
        "metrics/src",
        "preview/src",
    ] {
        rust_files(&root.join(dir), &mut files);
    }
    assert!(files.len() > 20, "found the sources");
    let mut found = Vec::new();
    for f in files {
        if f.ends_with("out_folder.rs") {
            continue;
        }
        let text = std::fs::read_to_string(&f).expect("source reads");
        // Production code only: a file's tests come after its `#[cfg(test)]`.
        let code = text.split("#[cfg(test)]").next().unwrap_or_default();
        for (n, line) in code.lines().enumerate() {
            let line = line.split("//").next().unwrap_or_default();
            if let Some(call) = CHANGES.iter().find(|c| line.contains(*c)) {
                found.push(format!("{}:{}: {call}", f.display(), n + 1));
            }
        }
    }
    assert!(
        found.is_empty(),
        "file-system changes outside src/out_folder.rs:\n{}",
        found.join("\n")
    );
}
