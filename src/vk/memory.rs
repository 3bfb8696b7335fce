//! Buffers and their memory (gpu-allocator), with upload and download through staging buffers.

use super::context::Context;
use super::error::{Error, Result, VkResultExt};
use ash::vk;
use gpu_allocator::MemoryLocation;
use gpu_allocator::vulkan::{
    Allocation, AllocationCreateDesc, AllocationScheme, AllocatorCreateDesc,
};
use std::sync::Mutex;

/// The largest staging buffer an upload makes; larger data is copied through it in turn.
pub const STAGING_BYTES: usize = 64 << 20;

/// gpu-allocator behind a lock; emptied before the device is destroyed.
pub struct Allocator(Mutex<Option<gpu_allocator::vulkan::Allocator>>);

impl Allocator {
    pub(crate) fn new(
        instance: &ash::Instance,
        device: &ash::Device,
        pd: vk::PhysicalDevice,
    ) -> Result<Allocator> {
        let a = gpu_allocator::vulkan::Allocator::new(&AllocatorCreateDesc {
            instance: instance.clone(),
            device: device.clone(),
            physical_device: pd,
            debug_settings: Default::default(),
            buffer_device_address: true,
            allocation_sizes: Default::default(),
        })
        .map_err(|source| Error::Allocation {
            what: "the allocator".into(),
            source,
        })?;
        Ok(Allocator(Mutex::new(Some(a))))
    }

    pub(crate) fn shutdown(&self) {
        if let Ok(mut a) = self.0.lock() {
            a.take();
        }
    }

    fn with<R>(&self, f: impl FnOnce(&mut gpu_allocator::vulkan::Allocator) -> R) -> R {
        let mut guard = self.0.lock().unwrap_or_else(|p| p.into_inner());
        f(guard.as_mut().expect("allocator used after shutdown"))
    }
}

/// A buffer with its memory and device address. Freed on drop.
pub struct Buffer {
    ctx: Context,
    pub buffer: vk::Buffer,
    allocation: Option<Allocation>,
    pub size: u64,
    /// Device address (0 unless created with SHADER_DEVICE_ADDRESS usage).
    pub address: u64,
}

impl Buffer {
    /// The mapped bytes of a host-visible buffer.
    pub fn mapped(&mut self) -> Option<&mut [u8]> {
        let size = self.size as usize;
        self.allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .map(|s| &mut s[..size])
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        if let Some(a) = self.allocation.take() {
            let _ = self.ctx.allocator.with(|al| al.free(a));
        }
        // SAFETY: the buffer was created on this device and no submitted work uses it any more
        // (every submission is waited for before the function that made it returns).
        unsafe { self.ctx.device.destroy_buffer(self.buffer, None) };
    }
}

impl Context {
    pub fn create_buffer(
        &self,
        name: &str,
        size: u64,
        usage: vk::BufferUsageFlags,
        location: MemoryLocation,
    ) -> Result<Buffer> {
        let size = size.max(16);
        let usage = usage | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        // SAFETY: valid device; the buffer is owned by the returned Buffer.
        unsafe {
            let buffer = self
                .device
                .create_buffer(
                    &vk::BufferCreateInfo::default()
                        .size(size)
                        .usage(usage)
                        .sharing_mode(vk::SharingMode::EXCLUSIVE),
                    None,
                )
                .vk("vkCreateBuffer")?;
            let mut req = self.device.get_buffer_memory_requirements(buffer);
            // Acceleration-structure inputs and scratch want more than the buffer reports on some
            // drivers; 256 covers every vendor's minAccelerationStructureScratchOffsetAlignment.
            req.alignment = req.alignment.max(256);
            let alloc = self.allocator.with(|a| {
                a.allocate(&AllocationCreateDesc {
                    name,
                    requirements: req,
                    location,
                    linear: true,
                    allocation_scheme: AllocationScheme::GpuAllocatorManaged,
                })
            });
            let alloc = match alloc {
                Ok(a) => a,
                Err(source) => {
                    self.device.destroy_buffer(buffer, None);
                    return Err(Error::Allocation {
                        what: format!("buffer \"{name}\" ({size} bytes)"),
                        source,
                    });
                }
            };
            if let Err(e) = self
                .device
                .bind_buffer_memory(buffer, alloc.memory(), alloc.offset())
            {
                let _ = self.allocator.with(|a| a.free(alloc));
                self.device.destroy_buffer(buffer, None);
                return Err(Error::from_call("vkBindBufferMemory", e));
            }
            let address = self
                .device
                .get_buffer_device_address(&vk::BufferDeviceAddressInfo::default().buffer(buffer));
            Ok(Buffer {
                ctx: self.clone(),
                buffer,
                allocation: Some(alloc),
                size,
                address,
            })
        }
    }

    /// A device-local buffer holding `data` (copied through a staging buffer).
    pub fn upload<T: bytemuck::Pod>(
        &self,
        name: &str,
        data: &[T],
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        self.upload_parts(name, &[bytemuck::cast_slice(data)], usage)
    }

    /// A device-local buffer holding `parts` one after the other, copied from where they are
    /// (a scene's textures, a dome's tables) without first joining them on the host.
    pub fn upload_parts(
        &self,
        name: &str,
        parts: &[&[u8]],
        usage: vk::BufferUsageFlags,
    ) -> Result<Buffer> {
        let size: u64 = parts.iter().map(|p| p.len() as u64).sum();
        self.uploads
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.uploaded_bytes
            .fetch_add(size, std::sync::atomic::Ordering::Relaxed);
        let dst = self.create_buffer(
            name,
            size,
            usage | vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuOnly,
        )?;
        let mut offset = 0;
        for part in parts {
            self.stage(name, &dst, offset, part)?;
            offset += part.len() as u64;
        }
        Ok(dst)
    }

    /// Overwrites `dst` (made by [`Context::upload`]) from byte `offset` with `data`, through a
    /// staging buffer; counted as an upload.
    pub fn write<T: bytemuck::Pod>(&self, dst: &Buffer, offset: u64, data: &[T]) -> Result<()> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        if offset + bytes.len() as u64 > dst.size {
            return Err(Error::Invalid(format!(
                "{} bytes do not fit a buffer of {}",
                bytes.len(),
                dst.size
            )));
        }
        self.uploads
            .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        self.uploaded_bytes
            .fetch_add(bytes.len() as u64, std::sync::atomic::Ordering::Relaxed);
        self.stage("write", dst, offset, bytes)
    }

    /// Copies `bytes` into `dst` at `offset` through a staging buffer of at most
    /// [`STAGING_BYTES`], in turn, and waits: a large upload never doubles in host memory.
    fn stage(&self, name: &str, dst: &Buffer, offset: u64, bytes: &[u8]) -> Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        let chunk = bytes.len().min(STAGING_BYTES);
        let mut staging = self.create_buffer(
            &format!("{name} (staging)"),
            chunk as u64,
            vk::BufferUsageFlags::TRANSFER_SRC,
            MemoryLocation::CpuToGpu,
        )?;
        for (k, piece) in bytes.chunks(chunk).enumerate() {
            staging
                .mapped()
                .ok_or_else(|| Error::Invalid("staging buffer is not host visible".into()))?
                [..piece.len()]
                .copy_from_slice(piece);
            let at = offset + (k * chunk) as u64;
            self.one_shot(|cmd| {
                // SAFETY: both buffers are alive until the submission completes; every earlier
                // submission using `dst` or the staging buffer has completed (one_shot waits).
                unsafe {
                    self.device.cmd_copy_buffer(
                        cmd,
                        staging.buffer,
                        dst.buffer,
                        &[vk::BufferCopy::default()
                            .dst_offset(at)
                            .size(piece.len() as u64)],
                    )
                }
            })?;
        }
        Ok(())
    }

    /// Buffers uploaded so far through [`Context::upload`], and their bytes.
    pub fn upload_counts(&self) -> (u64, u64) {
        use std::sync::atomic::Ordering::Relaxed;
        (
            self.uploads.load(Relaxed),
            self.uploaded_bytes.load(Relaxed),
        )
    }

    /// Reads `count` elements of `buf` back to the host.
    pub fn download<T: bytemuck::Pod>(&self, buf: &Buffer, count: usize) -> Result<Vec<T>> {
        let bytes = (count * std::mem::size_of::<T>()) as u64;
        let mut staging = self.create_buffer(
            "download (staging)",
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            MemoryLocation::GpuToCpu,
        )?;
        if bytes > 0 {
            self.one_shot(|cmd| {
                // SAFETY: both buffers are alive until the submission completes.
                unsafe {
                    self.device.cmd_copy_buffer(
                        cmd,
                        buf.buffer,
                        staging.buffer,
                        &[vk::BufferCopy::default().size(bytes)],
                    )
                }
            })?;
        }
        let mapped = staging
            .mapped()
            .ok_or_else(|| Error::Invalid("readback buffer is not host visible".into()))?;
        let mut out = vec![T::zeroed(); count];
        bytemuck::cast_slice_mut::<T, u8>(&mut out).copy_from_slice(&mapped[..bytes as usize]);
        Ok(out)
    }
}
