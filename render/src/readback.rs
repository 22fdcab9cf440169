//! Copies render targets into mappable buffers and reads them back without padding.

use crate::error::RenderError;

/// A texture-to-buffer copy in flight: the buffer and its row layout.
pub(crate) struct Readback {
    buffer: wgpu::Buffer,
    /// Bytes per row in the buffer (a multiple of 256).
    padded_row: u32,
    /// Bytes per row of actual pixels.
    row: u32,
    height: u32,
}

/// `width * bytes_per_pixel` rounded up to wgpu's 256-byte row alignment.
pub(crate) fn padded_row_bytes(width: u32, bytes_per_pixel: u32) -> u64 {
    let align = u64::from(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    (u64::from(width) * u64::from(bytes_per_pixel)).div_ceil(align) * align
}

impl Readback {
    /// Records a copy of the whole `texture` into a new buffer.
    pub(crate) fn record(
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        texture: &wgpu::Texture,
        bytes_per_pixel: u32,
    ) -> Readback {
        let size = texture.size();
        let row = size.width * bytes_per_pixel;
        // The caller checked that the padded size fits the device limits.
        let padded_row = padded_row_bytes(size.width, bytes_per_pixel) as u32;
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("frond-render readback"),
            size: u64::from(padded_row) * u64::from(size.height),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        encoder.copy_texture_to_buffer(
            wgpu::TexelCopyTextureInfo {
                texture,
                mip_level: 0,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(padded_row),
                    rows_per_image: Some(size.height),
                },
            },
            size,
        );
        Readback {
            buffer,
            padded_row,
            row,
            height: size.height,
        }
    }

    /// Maps the buffers after the copies were submitted, waits for the GPU, and
    /// returns each image's tightly packed rows (top row first).
    pub(crate) fn read_all(
        device: &wgpu::Device,
        readbacks: &[Readback],
    ) -> Result<Vec<Vec<u8>>, RenderError> {
        let (sender, receiver) = std::sync::mpsc::channel();
        for (i, readback) in readbacks.iter().enumerate() {
            let sender = sender.clone();
            readback
                .buffer
                .map_async(wgpu::MapMode::Read, .., move |result| {
                    // The receiver outlives the poll below; a send failure only means
                    // nobody is waiting any more.
                    let _ = sender.send((i, result));
                });
        }
        drop(sender);
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| RenderError::Readback(format!("waiting for the GPU failed: {e}")))?;

        // Another thread polling the same device may have taken our callbacks
        // and fire them only after our poll returned: wait for every callback
        // (each holds a sender; all of them gone means all of them ran),
        // polling again meanwhile, with a deadline so a lost one cannot hang.
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
        let mut mapped = vec![false; readbacks.len()];
        loop {
            match receiver.recv_timeout(std::time::Duration::from_millis(20)) {
                Ok((i, result)) => {
                    result.map_err(|e| {
                        RenderError::Readback(format!("mapping the buffer failed: {e}"))
                    })?;
                    mapped[i] = true;
                }
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {
                    if std::time::Instant::now() > deadline {
                        break;
                    }
                    device.poll(wgpu::PollType::Poll).map_err(|e| {
                        RenderError::Readback(format!("waiting for the GPU failed: {e}"))
                    })?;
                }
            }
        }
        if mapped.iter().any(|m| !m) {
            return Err(RenderError::Readback(
                "the GPU finished but a readback buffer was never mapped".into(),
            ));
        }

        readbacks.iter().map(Readback::unpad).collect()
    }

    fn unpad(&self) -> Result<Vec<u8>, RenderError> {
        let view = self
            .buffer
            .get_mapped_range(..)
            .map_err(|e| RenderError::Readback(format!("reading the mapped buffer failed: {e}")))?;
        let mut out = Vec::with_capacity(self.row as usize * self.height as usize);
        for row in view.chunks_exact(self.padded_row as usize) {
            out.extend_from_slice(&row[..self.row as usize]);
        }
        drop(view);
        self.buffer.unmap();
        Ok(out)
    }
}
