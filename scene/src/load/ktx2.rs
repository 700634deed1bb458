//! KTX2 images (KHR_texture_basisu's, and plain KTX2 textures): mip level 0 of layer 0, face
//! 0, decoded to RGBA.
//!
//! * The container (header, level index, data format descriptor) is parsed by the `ktx2` crate.
//! * Basis Universal payloads, ETC1S (BasisLZ) and UASTC (with or without Zstandard), are
//!   transcoded to RGBA8 by Binomial's transcoder (`basisu_c_sys`).
//! * Plain formats: R8G8B8(A8) and B8G8R8A8 UNORM/SRGB and R16G16B16A16 UNORM are read as 8-bit
//!   values; R16G16B16A16 and R32G32B32A32 SFLOAT as linear floats; BC1-BC5, BC7, ETC2/EAC and
//!   ASTC LDR blocks are decoded by `texture2ddecoder`. Any other format, a supercompressed
//!   plain format and a 3D texture are refused with a message naming them.
//!
//! The transfer function the data format descriptor declares is reported, not applied: the
//! texture slot that uses the image decides how its 8-bit values are read (see
//! [`crate::ColorSpace`]); the caller warns where the two disagree.

use ktx2::{Format, TransferFunction};

/// The twelve bytes every KTX2 file starts with (KTX 2.0 specification, §3.1).
const MAGIC: [u8; 12] = [0xAB, b'K', b'T', b'X', b' ', b'2', b'0', 0xBB, b'\r', b'\n', 0x1A, b'\n'];

/// Whether `bytes` are a KTX2 file (by its identifier, whatever the image's `mimeType` says).
pub(super) fn is_ktx2(bytes: &[u8]) -> bool {
    bytes.starts_with(&MAGIC)
}

/// The texels of a decoded level 0, row 0 at the top.
pub(super) enum Texels {
    /// 8-bit values (16-bit ones rounded to 8 bits); `srgb`: the descriptor declares the sRGB
    /// transfer function.
    Unorm8 { texels: Vec<[u8; 4]>, srgb: bool },
    /// Linear floating-point values (KTX2 requires a linear transfer for the float formats).
    Float(Vec<[f32; 4]>),
}

/// A decoded KTX2 image.
pub(super) struct Decoded {
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) texels: Texels,
    /// What was decoded, for messages (`UASTC`, `BC7_SRGB_BLOCK`...).
    pub(super) format: String,
}

/// Decodes level 0 of a KTX2 file, refusing images wider or taller than `max_size`. Corrupt
/// data is an `Err` with the reason, never a panic: the transcoders are also run under
/// `catch_unwind`, the last line of defence should one of them panic on data it does not
/// expect.
pub(super) fn decode(bytes: &[u8], max_size: u32) -> Result<Decoded, String> {
    std::panic::catch_unwind(|| decode_unguarded(bytes, max_size))
        .unwrap_or_else(|_| Err("the KTX2 decoder failed on corrupt data".into()))
}

fn decode_unguarded(bytes: &[u8], max_size: u32) -> Result<Decoded, String> {
    let reader = ktx2::Reader::new(bytes).map_err(|e| format!("not a valid KTX2 file: {e}"))?;
    let header = reader.header();
    let (width, height) = (header.pixel_width, header.pixel_height.max(1));
    if header.pixel_depth > 1 {
        return Err(format!(
            "a 3D texture ({width} × {height} × {}): only 2D textures are supported",
            header.pixel_depth
        ));
    }
    if width > max_size || height > max_size {
        return Err(format!("{width} × {height} texels: a texture may have at most {max_size} × {max_size}"));
    }
    let srgb = reader.transfer_function() == Some(TransferFunction::SRGB);
    let Some(format) = header.format else {
        return transcode_basis(bytes, width, height);
    };
    if let Some(scheme) = header.supercompression_scheme {
        return Err(format!("{format:?} texels with {scheme:?} supercompression are not supported"));
    }
    let level = reader.levels().next().ok_or("no mip level")?;
    let (w, h) = (width as usize, height as usize);
    let name = format!("{format:?}");
    let unorm8 =
        |texels| Ok(Decoded { width, height, texels: Texels::Unorm8 { texels, srgb }, format: name.clone() });
    let float = |texels| Ok(Decoded { width, height, texels: Texels::Float(texels), format: name.clone() });
    match format {
        Format::R8G8B8A8_UNORM | Format::R8G8B8A8_SRGB => {
            unorm8(texels_of(level.data, w * h, 4, |t| [t[0], t[1], t[2], t[3]])?)
        }
        Format::B8G8R8A8_UNORM | Format::B8G8R8A8_SRGB => {
            unorm8(texels_of(level.data, w * h, 4, |t| [t[2], t[1], t[0], t[3]])?)
        }
        Format::R8G8B8_UNORM | Format::R8G8B8_SRGB => {
            unorm8(texels_of(level.data, w * h, 3, |t| [t[0], t[1], t[2], 255])?)
        }
        Format::R16G16B16A16_UNORM => unorm8(texels_of(level.data, w * h, 8, |t| {
            // v / 65535 rounded to the nearest of 0..=255 (65535 = 255 · 257).
            std::array::from_fn(|c| {
                ((u32::from(u16::from_le_bytes([t[2 * c], t[2 * c + 1]])) + 128) / 257) as u8
            })
        })?),
        Format::R16G16B16A16_SFLOAT => float(texels_of(level.data, w * h, 8, |t| {
            std::array::from_fn(|c| half::f16::from_le_bytes([t[2 * c], t[2 * c + 1]]).to_f32())
        })?),
        Format::R32G32B32A32_SFLOAT => float(texels_of(level.data, w * h, 16, |t| {
            std::array::from_fn(|c| f32::from_le_bytes([t[4 * c], t[4 * c + 1], t[4 * c + 2], t[4 * c + 3]]))
        })?),
        _ => unorm8(decode_blocks(format, level.data, w, h)?),
    }
}

/// `count` texels of `stride` bytes each from the start of `data`, converted by `texel`.
fn texels_of<T>(
    data: &[u8],
    count: usize,
    stride: usize,
    texel: impl Fn(&[u8]) -> T,
) -> Result<Vec<T>, String> {
    let need = count.checked_mul(stride).ok_or("level 0 is too large")?;
    let data =
        data.get(..need).ok_or_else(|| format!("level 0 has {} bytes, {need} expected", data.len()))?;
    Ok(data.chunks_exact(stride).map(texel).collect())
}

/// A texture2ddecoder function: blocks to `width × height` texels (`u32`s whose little-endian
/// bytes are B, G, R, A).
type BlockDecoder = fn(&[u8], usize, usize, &mut [u32]) -> Result<(), &'static str>;

/// Decodes a block-compressed level with texture2ddecoder.
fn decode_blocks(format: Format, data: &[u8], w: usize, h: usize) -> Result<Vec<[u8; 4]>, String> {
    use texture2ddecoder as t;
    let v = format.value();
    // The ASTC formats: UNORM then SRGB for each footprint, VK_FORMAT_ASTC_4x4_UNORM_BLOCK (157)
    // to VK_FORMAT_ASTC_12x12_SRGB_BLOCK (184), footprints in this order.
    const ASTC: [(usize, usize); 14] = [
        (4, 4),
        (5, 4),
        (5, 5),
        (6, 5),
        (6, 6),
        (8, 5),
        (8, 6),
        (8, 8),
        (10, 5),
        (10, 6),
        (10, 8),
        (10, 10),
        (12, 10),
        (12, 12),
    ];
    let mut out = vec![0u32; w * h];
    let result = if (157..=184).contains(&v) {
        let (bw, bh) = ASTC[(v - 157) as usize / 2];
        t::decode_astc(data, w, h, bw, bh, &mut out)
    } else {
        let decoder: BlockDecoder = match format {
            Format::BC1_RGB_UNORM_BLOCK | Format::BC1_RGB_SRGB_BLOCK => t::decode_bc1,
            Format::BC1_RGBA_UNORM_BLOCK | Format::BC1_RGBA_SRGB_BLOCK => t::decode_bc1a,
            Format::BC2_UNORM_BLOCK | Format::BC2_SRGB_BLOCK => t::decode_bc2,
            Format::BC3_UNORM_BLOCK | Format::BC3_SRGB_BLOCK => t::decode_bc3,
            Format::BC4_UNORM_BLOCK => t::decode_bc4,
            Format::BC5_UNORM_BLOCK => t::decode_bc5,
            Format::BC7_UNORM_BLOCK | Format::BC7_SRGB_BLOCK => t::decode_bc7,
            Format::ETC2_R8G8B8_UNORM_BLOCK | Format::ETC2_R8G8B8_SRGB_BLOCK => t::decode_etc2_rgb,
            Format::ETC2_R8G8B8A1_UNORM_BLOCK | Format::ETC2_R8G8B8A1_SRGB_BLOCK => t::decode_etc2_rgba1,
            Format::ETC2_R8G8B8A8_UNORM_BLOCK | Format::ETC2_R8G8B8A8_SRGB_BLOCK => t::decode_etc2_rgba8,
            Format::EAC_R11_UNORM_BLOCK => t::decode_eacr,
            Format::EAC_R11G11_UNORM_BLOCK => t::decode_eacrg,
            other => return Err(format!("{other:?} texels are not supported")),
        };
        decoder(data, w, h, &mut out)
    };
    result.map_err(|e| format!("{format:?}: {e}"))?;
    Ok(out
        .into_iter()
        .map(|p| {
            let [b, g, r, a] = p.to_le_bytes();
            [r, g, b, a]
        })
        .collect())
}

/// Transcodes a Basis Universal payload (ETC1S or UASTC) to RGBA8 with Binomial's transcoder.
fn transcode_basis(bytes: &[u8], width: u32, height: u32) -> Result<Decoded, String> {
    use basisu_c_sys::extra::{BasisuTranscoder, ChannelType, SupportedTextureCompression};
    basisu_c_sys::extra::basisu_transcoder_init();
    let transcoder = BasisuTranscoder::new(bytes, SupportedTextureCompression::empty(), ChannelType::Auto)
        .map_err(|e| format!("Basis Universal: {e}"))?;
    let info = transcoder.get_info();
    let kind = match info.basis_format {
        basisu_c_sys::BasisTextureFormat::Etc1s => "ETC1S",
        basisu_c_sys::BasisTextureFormat::UastcLdr4x4 => "UASTC",
        other => {
            return Err(format!("Basis Universal format {other:?} is not supported (ETC1S and UASTC are)"));
        }
    };
    if (info.width, info.height.max(1)) != (width, height) {
        return Err(format!(
            "{kind}: the transcoder reads {} × {}, the header says {width} × {height}",
            info.width, info.height
        ));
    }
    let image = transcoder
        .transcode(Some(basisu_c_sys::TranscodeTargetFormat::RGBA32), Some(info.is_srgb))
        .map_err(|e| format!("{kind}: {e}"))?;
    // Level 0, layer 0, face 0 comes first (the levels follow, largest first).
    let texels = texels_of(&image.data, width as usize * height as usize, 4, |t| [t[0], t[1], t[2], t[3]])
        .map_err(|e| format!("{kind}: {e}"))?;
    let srgb = info.is_srgb;
    Ok(Decoded { width, height, texels: Texels::Unorm8 { texels, srgb }, format: kind.into() })
}
