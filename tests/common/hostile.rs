//! The bad-input corpus: reproducers of what an attacker tried, made from the bundled sample at
//! test time (some are megabytes of JSON or declare gigabytes of texels, none is worth
//! committing), and a runner that measures what a refusal costs.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::{Value, json};

/// A GLB as its JSON and BIN chunks.
pub struct Glb {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl Glb {
    /// Reads a GLB.
    pub fn read(path: &Path) -> Glb {
        let bytes = std::fs::read(path).expect("GLB reads");
        let glb = gltf::binary::Glb::from_slice(&bytes).expect("a GLB");
        Glb {
            json: serde_json::from_slice(&glb.json).expect("JSON chunk"),
            bin: glb.bin.map(|b| b.into_owned()).unwrap_or_default(),
        }
    }

    /// The bundled sample.
    pub fn sample() -> Glb {
        Glb::read(&super::root().join("samples/sapling.glb"))
    }

    /// Writes it as `dir/name`.
    pub fn write(&self, dir: &Path, name: &str) -> PathBuf {
        let mut json = self.json.clone();
        json["buffers"][0]["byteLength"] = json!(self.bin.len());
        let text = serde_json::to_vec(&json).expect("JSON");
        let path = dir.join(name);
        std::fs::write(
            &path,
            frond_scene::gltf_writer::glb_container(&text, &self.bin),
        )
        .expect("GLB written");
        path
    }

    /// Appends `bytes` as an image (in a buffer view) with a texture; returns the texture.
    pub fn add_image(&mut self, name: &str, mime: &str, bytes: &[u8]) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let push = |v: &mut Value, key: &str, item: Value| -> usize {
            if v.get(key).is_none() {
                v[key] = json!([]);
            }
            let a = v[key].as_array_mut().expect("array");
            a.push(item);
            a.len() - 1
        };
        let view = push(
            &mut self.json,
            "bufferViews",
            json!({ "buffer": 0, "byteOffset": offset, "byteLength": bytes.len() }),
        );
        let image = push(
            &mut self.json,
            "images",
            json!({ "bufferView": view, "mimeType": mime, "name": name }),
        );
        push(&mut self.json, "textures", json!({ "source": image }))
    }

    /// Appends a KTX2 image reached only through `KHR_texture_basisu`; returns the texture.
    pub fn add_ktx2(&mut self, name: &str, bytes: &[u8]) -> usize {
        let t = self.add_image(name, "image/ktx2", bytes);
        let image = self.json["textures"][t]["source"].clone();
        self.json["textures"][t] =
            json!({ "extensions": { "KHR_texture_basisu": { "source": image } } });
        for key in ["extensionsUsed", "extensionsRequired"] {
            let list = self.json[key].as_array().cloned().unwrap_or_default();
            if !list.contains(&json!("KHR_texture_basisu")) {
                let mut list = list;
                list.push(json!("KHR_texture_basisu"));
                self.json[key] = Value::Array(list);
            }
        }
        t
    }

    /// The accessor of attribute `attribute` of the first primitive of the mesh named `mesh`.
    pub fn attribute(&self, mesh: &str, attribute: &str) -> usize {
        let m = self.json["meshes"]
            .as_array()
            .expect("meshes")
            .iter()
            .find(|m| m["name"] == mesh)
            .expect("the mesh");
        m["primitives"][0]["attributes"][attribute]
            .as_u64()
            .expect("the attribute") as usize
    }

    /// Where accessor `a`'s first element starts in the BIN chunk.
    pub fn accessor_offset(&self, a: usize) -> usize {
        let accessor = &self.json["accessors"][a];
        let view = accessor["bufferView"].as_u64().expect("a view") as usize;
        self.json["bufferViews"][view]["byteOffset"]
            .as_u64()
            .unwrap_or(0) as usize
            + accessor["byteOffset"].as_u64().unwrap_or(0) as usize
    }

    /// Sets material `m`'s map at `pointer` (`/normalTexture`,
    /// `/pbrMetallicRoughness/metallicRoughnessTexture`, ...) to texture `t`.
    pub fn set_map(&mut self, m: usize, pointer: &str, t: usize) {
        let mut at = &mut self.json["materials"][m];
        for part in pointer.trim_start_matches('/').split('/') {
            at = &mut at[part];
        }
        *at = json!({ "index": t });
    }
}

/// A PNG whose header declares `w`×`h` RGBA pixels with almost no data: what a "texture bomb"
/// looks like to a reader that trusts headers.
pub fn png_header_only(w: u32, h: u32) -> Vec<u8> {
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut out = (data.len() as u32).to_be_bytes().to_vec();
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        out.extend_from_slice(&body);
        out.extend_from_slice(&crc32(&body).to_be_bytes());
        out
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    png.extend(chunk(b"IHDR", &ihdr));
    // A zlib stream of one empty stored block: far too little data for the declared size.
    png.extend(chunk(
        b"IDAT",
        &[0x78, 0x01, 0x01, 0x00, 0x00, 0xff, 0xff, 0, 0, 0, 1],
    ));
    png.extend(chunk(b"IEND", &[]));
    png
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xffff_ffffu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xedb8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A valid PNG of `w`×`h` pixels of one colour (RGB), written row by row (a few kilobytes for
/// any size).
pub fn png_solid(w: u32, h: u32, rgb: [u8; 3]) -> Vec<u8> {
    let mut out = Vec::new();
    {
        let mut e = png::Encoder::new(&mut out, w, h);
        e.set_color(png::ColorType::Rgb);
        e.set_depth(png::BitDepth::Eight);
        e.set_compression(png::Compression::Fast);
        let mut writer = e.write_header().expect("header");
        let mut stream = writer.stream_writer().expect("stream");
        let row: Vec<u8> = (0..w).flat_map(|_| rgb).collect();
        for _ in 0..h {
            std::io::Write::write_all(&mut stream, &row).expect("row");
        }
        stream.finish().expect("finished");
    }
    out
}

/// A UASTC KTX2 of `w`×`h` texels (multiples of 4) of one colour: one real block, repeated,
/// Zstandard-compressed to a few kilobytes.
pub fn ktx2_solid(w: u32, h: u32) -> Vec<u8> {
    let block = frond_scene::ktx2::uastc_blocks(&[(4, 4, [90u8, 140, 200, 255].repeat(16))], false)
        .expect("a 4×4 block encodes");
    let tiled = block[0].repeat((w / 4) as usize * (h / 4) as usize);
    frond_scene::ktx2::uastc_container(w, h, &[tiled], false, false)
}

/// A KTX2 whose header declares `w`×`h` texels and holds one block.
pub fn ktx2_header_only(w: u32, h: u32) -> Vec<u8> {
    frond_scene::ktx2::uastc_container(w, h, &[vec![0u8; 16]], false, false)
}

/// What one run cost.
pub struct Measured {
    pub output: Output,
    pub wall: Duration,
    /// Peak resident memory of the process, bytes: the largest `VmHWM` read from
    /// `/proc/<pid>/status` while it ran (read every millisecond; the process's own high-water
    /// mark, unlike `wait4`'s `ru_maxrss`, which Linux carries over from the spawning test
    /// process).
    pub peak_rss: u64,
}

impl Measured {
    pub fn stderr(&self) -> String {
        String::from_utf8_lossy(&self.output.stderr).into_owned()
    }

    /// Its time and peak memory in words.
    pub fn summary(&self) -> String {
        format!(
            "{:.2} s, peak {} MB",
            self.wall.as_secs_f64(),
            self.peak_rss >> 20
        )
    }
}

/// `VmHWM` of process `pid`, bytes (None once it has exited).
fn high_water(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kb * 1024)
}

/// Runs frond with `args`, measuring its wall time and peak memory; killed after `limit`.
pub fn frond_measured(args: &[&str], limit: Duration) -> Measured {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_frond"))
        .args(args)
        .env("XDG_RUNTIME_DIR", std::env::temp_dir())
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("frond runs");
    let pid = child.id();
    let (mut out, mut err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let read_out = std::thread::spawn(move || {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut out, &mut v).ok();
        v
    });
    let read_err = std::thread::spawn(move || {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut err, &mut v).ok();
        v
    });
    let mut peak = 0u64;
    let status = loop {
        if let Some(hwm) = high_water(pid) {
            peak = peak.max(hwm);
        }
        if let Some(status) = child.try_wait().expect("wait") {
            break status;
        }
        if start.elapsed() > limit {
            let _ = child.kill();
            break child.wait().expect("wait");
        }
        std::thread::sleep(Duration::from_millis(1));
    };
    let wall = start.elapsed();
    Measured {
        output: Output {
            status,
            stdout: read_out.join().unwrap_or_default(),
            stderr: read_err.join().unwrap_or_default(),
        },
        wall,
        peak_rss: peak,
    }
}
