//! Linear RGB OpenEXR output and input through the `exr` crate, with render metadata stored as
//! text attributes.

use crate::PostError;
use crate::atomic::{Staged, stage};
use exr::prelude::{
    AnyChannel, AnyChannels, AttributeValue, Encoding, FlatSamples, Image, Layer, LayerAttributes,
    ReadChannels, ReadLayers, SmallVec, SpecificChannels, Text, Vec2, WritableImage, read,
};
use furnace_render::{AovSum, Film};
use glam::{DVec3, Vec3};
use std::collections::{BTreeMap, HashMap};
use std::fs::File;
use std::io::{BufReader, BufWriter, Seek, SeekFrom, Write};
use std::path::Path;

/// The largest width and height of an image furnace reads: the largest film it renders
/// (`furnace render --width/--height` stop there too). A header claiming more is refused before
/// anything is allocated for its pixels: a film of 16384² pixels with its resume state already
/// takes tens of gigabytes, and an image side of 100000 in a file of a few hundred bytes would
/// otherwise ask the allocator for terabytes.
pub const MAX_IMAGE_SIDE: u32 = 16_384;

/// The most bytes of uncompressed pixel data an EXR is believed to hold per byte of file.
/// The `exr` crate allocates every channel of a layer at its full size before it decodes a
/// block, so a small file claiming a large image (within [`MAX_IMAGE_SIDE`]) would still cost
/// gigabytes before its missing blocks are noticed; such a file is refused from its header. No
/// codec the crate reads does better than zlib's 1032:1 (ZIP; PXR24 on `f32` data 4/3 of that,
/// after it drops a byte per sample; RLE 64:1, PIZ and B44 less; measured on a one-colour image
/// by the `constant_images_compress_below_the_bound` test: at most about 330:1), so 2¹² refuses
/// no real file while bounding a hostile one's pixel memory to 4 KiB per byte of file.
pub const MAX_COMPRESSION_RATIO: u64 = 1 << 12;

/// Render metadata stored in an EXR header as text attributes.
///
/// The named fields are written as `furnace.spp`, `furnace.sampler`, `furnace.bounces`,
/// `furnace.seed`, `furnace.scene`, `furnace.renderTimeS` and `furnace.rejectedSamples`
/// (numbers in decimal; the render time with Rust's shortest round-trip `f64` formatting, so it
/// reads back bit-identical). A `None` field is not written. [`Metadata::extra`] entries are
/// written under their own key, verbatim.
///
/// On reading, the `furnace.*` attributes fill the named fields and every other text
/// attribute of the header (e.g. Mitsuba's `generatedBy`) lands in `extra`. Values are stored as
/// UTF-8 bytes (EXR strings are byte strings); a value that is not UTF-8 is read as Latin-1.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Metadata {
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// The sampler's name (`sobol`, `pmj02`, …).
    pub sampler: Option<String>,
    /// The maximum path depth.
    pub bounces: Option<u32>,
    /// The sampler seed.
    pub seed: Option<u64>,
    /// The scene (file name or description).
    pub scene: Option<String>,
    /// Wall-clock render time in seconds.
    pub render_time_s: Option<f64>,
    /// Samples rejected as non-finite (NaN/∞) during the render.
    pub rejected_samples: Option<u64>,
    /// Any other key/value pairs. Keys must be printable ASCII, 1–255 bytes, and neither an
    /// OpenEXR standard attribute name nor one of the `furnace.*` names above.
    pub extra: BTreeMap<String, String>,
}

const SPP: &str = "furnace.spp";
const SAMPLER: &str = "furnace.sampler";
const BOUNCES: &str = "furnace.bounces";
const SEED: &str = "furnace.seed";
const SCENE: &str = "furnace.scene";
const RENDER_TIME: &str = "furnace.renderTimeS";
const REJECTED: &str = "furnace.rejectedSamples";
/// The film size of the resume state (`WxH`), written beside the state channels and checked
/// against the data window when the state is read: a file cropped or padded after furnace wrote
/// it is refused. Not part of [`Metadata`] (the file's own record of itself).
const STATE_SIZE: &str = "furnace.resume.size";
const FURNACE_KEYS: [&str; 8] = [SPP, SAMPLER, BOUNCES, SEED, SCENE, RENDER_TIME, REJECTED, STATE_SIZE];

/// Attribute names that the OpenEXR format (and the `exr` crate) give a meaning and a type;
/// an extra key may not take one of them.
const RESERVED: &[&str] = &[
    "tiles",
    "name",
    "type",
    "version",
    "chunkCount",
    "maxSamplesPerPixel",
    "channels",
    "compression",
    "dataWindow",
    "displayWindow",
    "lineOrder",
    "pixelAspectRatio",
    "screenWindowCenter",
    "screenWindowWidth",
    "whiteLuminance",
    "adoptedNeutral",
    "renderingTransform",
    "lookModTransform",
    "xDensity",
    "owner",
    "comments",
    "capDate",
    "utcOffset",
    "longitude",
    "latitude",
    "altitude",
    "focus",
    "expTime",
    "aperture",
    "isoSpeed",
    "envmap",
    "keyCode",
    "timeCode",
    "wrapmodes",
    "framesPerSecond",
    "multiView",
    "worldToCamera",
    "worldToNDC",
    "deepImageState",
    "originalDataWindow",
    "dwaCompressionLevel",
    "preview",
    "view",
    "chromaticities",
    "near",
    "far",
    "fieldOfViewHorizontal",
    "fieldOfViewVertical",
    "software",
];

impl Metadata {
    /// The header attributes: `(name, value)` pairs, named fields first.
    fn to_attributes(&self, path: &Path) -> Result<Vec<(String, String)>, PostError> {
        let mut out = Vec::new();
        let mut put = |k: &str, v: Option<String>| {
            if let Some(v) = v {
                out.push((k.to_string(), v));
            }
        };
        put(SPP, self.spp.map(|v| v.to_string()));
        put(SAMPLER, self.sampler.clone());
        put(BOUNCES, self.bounces.map(|v| v.to_string()));
        put(SEED, self.seed.map(|v| v.to_string()));
        put(SCENE, self.scene.clone());
        put(RENDER_TIME, self.render_time_s.map(|v| v.to_string()));
        put(REJECTED, self.rejected_samples.map(|v| v.to_string()));
        for (k, v) in &self.extra {
            let bad =
                |reason| PostError::InvalidMetadataKey { path: path.to_path_buf(), key: k.clone(), reason };
            if k.is_empty() || k.len() > 255 {
                return Err(bad("a key must be 1 to 255 bytes long"));
            }
            if !k.bytes().all(|b| b.is_ascii_graphic()) {
                return Err(bad("a key must be printable ASCII without spaces"));
            }
            if RESERVED.contains(&k.as_str()) {
                return Err(bad("it is an OpenEXR standard attribute name"));
            }
            if FURNACE_KEYS.contains(&k.as_str()) {
                return Err(bad("it is one of furnace's own metadata names; set the Metadata field instead"));
            }
            out.push((k.clone(), v.clone()));
        }
        Ok(out)
    }

    /// Fills the fields from text attributes; non-text attributes are ignored.
    fn from_attributes<'a>(
        path: &Path,
        attributes: impl Iterator<Item = (&'a Text, &'a AttributeValue)>,
    ) -> Result<Self, PostError> {
        let mut m = Metadata::default();
        for (name, value) in attributes {
            let AttributeValue::Text(text) = value else { continue };
            let key = text_to_string(name);
            let value = text_to_string(text);
            let bad = |expected| PostError::InvalidMetadataValue {
                path: path.to_path_buf(),
                key: key.clone(),
                value: value.clone(),
                expected,
            };
            match key.as_str() {
                SPP => m.spp = Some(value.parse().map_err(|_| bad("u32"))?),
                SAMPLER => m.sampler = Some(value),
                BOUNCES => m.bounces = Some(value.parse().map_err(|_| bad("u32"))?),
                SEED => m.seed = Some(value.parse().map_err(|_| bad("u64"))?),
                SCENE => m.scene = Some(value),
                RENDER_TIME => m.render_time_s = Some(value.parse().map_err(|_| bad("f64"))?),
                REJECTED => m.rejected_samples = Some(value.parse().map_err(|_| bad("u64"))?),
                // Checked by `read_exr_with_state`.
                STATE_SIZE => {}
                _ => {
                    m.extra.insert(key, value);
                }
            }
        }
        Ok(m)
    }
}

/// EXR text → `String`: UTF-8 if it is, else Latin-1 (the `exr` crate's reading).
fn text_to_string(text: &Text) -> String {
    match std::str::from_utf8(text.bytes()) {
        Ok(s) => s.to_string(),
        Err(_) => text.to_string(),
    }
}

/// Opens `path` for reading if it is a regular file (symbolic links followed); anything else
/// — a directory, a FIFO, a device, a socket — is refused before it is opened, so a FIFO cannot
/// block the reader and a device cannot feed it without end.
pub(crate) fn open_regular_file(path: &Path) -> Result<File, PostError> {
    let io_err = |source| PostError::Io { path: path.to_path_buf(), source };
    let kind = std::fs::metadata(path).map_err(io_err)?.file_type();
    if !kind.is_file() {
        return Err(PostError::NotAFile { path: path.to_path_buf(), kind: file_kind(kind) });
    }
    File::open(path).map_err(io_err)
}

/// What a file that is not a regular file is, for messages.
fn file_kind(kind: std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if kind.is_fifo() {
            return "a FIFO";
        }
        if kind.is_char_device() || kind.is_block_device() {
            return "a device";
        }
        if kind.is_socket() {
            return "a socket";
        }
    }
    if kind.is_dir() { "a directory" } else { "not a regular file" }
}

/// Opens the EXR at `path` (a regular file) and reads its headers, refusing an image larger than
/// [`MAX_IMAGE_SIDE`] or one claiming more pixel data than the file can hold
/// ([`MAX_COMPRESSION_RATIO`]) before any pixel is allocated; returns the file, at its start.
fn open_exr(path: &Path) -> Result<(File, exr::meta::MetaData), PostError> {
    let io_err = |source| PostError::Io { path: path.to_path_buf(), source };
    let mut file = open_regular_file(path)?;
    let file_bytes = file.metadata().map_err(io_err)?.len();
    let meta = exr::meta::MetaData::read_from_buffered(BufReader::new(&mut file), false)
        .map_err(|source| PostError::Exr { path: path.to_path_buf(), source })?;
    let mut claimed = 0u64;
    for header in &meta.headers {
        let (w, h) = (header.layer_size.0 as u64, header.layer_size.1 as u64);
        if w > u64::from(MAX_IMAGE_SIDE) || h > u64::from(MAX_IMAGE_SIDE) {
            return Err(PostError::TooLarge { path: path.to_path_buf(), width: w, height: h });
        }
        // At most 2^28 pixels times a byte count of the channel list: no overflow in u64 for
        // fewer than 2^36 bytes per pixel.
        let bytes = (w * h).saturating_mul(header.channels.bytes_per_pixel as u64);
        claimed = claimed.saturating_add(bytes);
        if claimed > file_bytes.saturating_mul(MAX_COMPRESSION_RATIO) {
            return Err(PostError::TooLittleData {
                path: path.to_path_buf(),
                width: w,
                height: h,
                claimed,
                file_bytes,
            });
        }
    }
    file.seek(SeekFrom::Start(0)).map_err(io_err)?;
    Ok((file, meta))
}

/// `Ok` if `len == width · height ≥ 1`, else [`PostError::SizeMismatch`].
pub(crate) fn check_size(path: &Path, width: u32, height: u32, len: usize) -> Result<(), PostError> {
    let expected = (width as usize).saturating_mul(height as usize);
    if expected == 0 || len != expected {
        return Err(PostError::SizeMismatch { path: path.to_path_buf(), width, height, expected, got: len });
    }
    Ok(())
}

/// Writes a linear RGB image as an OpenEXR file with 32-bit float `R`, `G`, `B` channels
/// (ZIP-compressed scan lines, lossless), rows top to bottom, and `metadata` as text attributes.
/// The write is atomic (temporary file + rename): an interrupted write never leaves a truncated
/// file at `path`, and a failed one leaves no temporary file.
///
/// # Errors
/// [`PostError::SizeMismatch`] if `pixels.len() != width · height` or the image is empty;
/// [`PostError::InvalidMetadataKey`] for an unusable extra key; [`PostError::Exr`] /
/// [`PostError::Io`] on encoding or file errors. All name `path`.
pub fn write_exr(
    path: impl AsRef<Path>,
    width: u32,
    height: u32,
    pixels: &[Vec3],
    metadata: &Metadata,
) -> Result<(), PostError> {
    let path = path.as_ref();
    check_size(path, width, height, pixels.len())?;
    let layer_attributes = layer_attributes(path, metadata)?;
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p.x, p.y, p.z)
    });
    let layer = Layer::new((w, height as usize), layer_attributes, Encoding::SMALL_LOSSLESS, channels);
    let image = Image::from_layer(layer);
    write_encoded(path, |out| image.write().to_buffered(out))
}

/// The metadata as the layer's text attributes.
fn layer_attributes(path: &Path, metadata: &Metadata) -> Result<LayerAttributes, PostError> {
    let mut other = HashMap::new();
    for (k, v) in metadata.to_attributes(path)? {
        other.insert(
            Text::from_slice_unchecked(k.as_bytes()),
            AttributeValue::Text(Text::from_slice_unchecked(v.as_bytes())),
        );
    }
    Ok(LayerAttributes { other, ..LayerAttributes::default() })
}

/// Writes `path` atomically with `encode`.
fn write_encoded(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<&mut File>) -> exr::error::Result<()>,
) -> Result<(), PostError> {
    stage_encoded(path, encode)?.commit()
}

/// Stages `path` ([`stage`]) with `encode`.
fn stage_encoded(
    path: &Path,
    encode: impl FnOnce(&mut BufWriter<&mut File>) -> exr::error::Result<()>,
) -> Result<Staged, PostError> {
    let exr_err = |source| PostError::Exr { path: path.to_path_buf(), source };
    stage(path, |file| {
        let mut out = BufWriter::new(file);
        encode(&mut out).map_err(exr_err)?;
        out.flush().map_err(|source| PostError::Io { path: path.to_path_buf(), source })
    })
}

/// Reads the first layer with `R`, `G`, `B` channels of an OpenEXR file as linear RGB:
/// `(width, height, pixels row-major top to bottom, metadata)`.
///
/// Reads what [`write_exr`] writes bit-identically, and other renderers' files: channels may be
/// f16, f32 or u32 (converted to f32), in any order (Mitsuba 3 writes `B`, `G`, `R` f32 with PIZ
/// compression); other channels such as `A` are ignored. The size is that of the data window.
///
/// # Errors
/// [`PostError::Exr`] if the file cannot be read or has no RGB layer;
/// [`PostError::InvalidMetadataValue`] if a `furnace.*` attribute does not parse. All name `path`.
pub fn read_exr(path: impl AsRef<Path>) -> Result<(u32, u32, Vec<Vec3>, Metadata), PostError> {
    let path = path.as_ref();
    let exr_err = |source| PostError::Exr { path: path.to_path_buf(), source };
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .rgb_channels(
            |size: Vec2<usize>, _| (size.0, vec![Vec3::ZERO; size.0 * size.1]),
            |(w, px): &mut (usize, Vec<Vec3>), Vec2(x, y): Vec2<usize>, (r, g, b): (f32, f32, f32)| {
                px[y * *w + x] = Vec3::new(r, g, b);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_buffered(BufReader::new(open_exr(path)?.0))
        .map_err(exr_err)?;
    let layer = &image.layer_data;
    let size = layer.size;
    let attributes = image.attributes.other.iter().chain(layer.attributes.other.iter());
    let metadata = Metadata::from_attributes(path, attributes)?;
    let (_, pixels) = &layer.channel_data.pixels;
    // The exr crate limits sizes to i32 range, so these fit.
    Ok((size.0 as u32, size.1 as u32, pixels.clone(), metadata))
}

/// The size and [`Metadata`] of an EXR written by [`write_exr`] or [`write_exr_with_state`],
/// read from its header alone (no pixel is decoded: milliseconds for a 4K film, where
/// [`read_exr_with_state`] takes seconds). The first part's header, as [`read_exr`] reads.
///
/// # Errors
/// [`PostError::Exr`] if the file is not a readable EXR; [`PostError::InvalidMetadataValue`] for
/// a furnace attribute that does not parse. Both name `path`.
pub fn read_exr_metadata(path: impl AsRef<Path>) -> Result<(u32, u32, Metadata), PostError> {
    let path = path.as_ref();
    let (_, meta) = open_exr(path)?;
    let Some(header) = meta.headers.first() else {
        return Err(PostError::Exr {
            path: path.to_path_buf(),
            source: exr::error::Error::Invalid("no header".into()),
        });
    };
    let attributes = header.shared_attributes.other.iter().chain(header.own_attributes.other.iter());
    let metadata = Metadata::from_attributes(path, attributes)?;
    // The exr crate limits sizes to i32 range, so these fit.
    Ok((header.layer_size.0 as u32, header.layer_size.1 as u32, metadata))
}

/// The layer (channel-name prefix) holding a progressive render's accumulation state.
///
/// Beside the `R`, `G`, `B` means (which viewers show as the image), [`write_exr_with_state`]
/// stores, in the same part, the `u32` channels `furnace.resume.count` (accepted samples per
/// pixel) and `furnace.resume.sumR.hi`, `furnace.resume.sumR.lo`, … `sumB.lo`: each pixel's
/// `f64` sum per colour channel as its IEEE-754 bit pattern split into high and low 32 bits. EXR
/// has no 64-bit sample type; the split keeps the sums exact, so a render resumed from the file
/// continues bit-identically.
pub const RESUME_LAYER: &str = "furnace.resume";

/// `furnace.resume.count`.
const COUNT_CHANNEL: &str = "furnace.resume.count";
/// `[high, low]` halves of the R, G, B sums.
const SUM_CHANNELS: [[&str; 2]; 3] = [
    ["furnace.resume.sumR.hi", "furnace.resume.sumR.lo"],
    ["furnace.resume.sumG.hi", "furnace.resume.sumG.lo"],
    ["furnace.resume.sumB.hi", "furnace.resume.sumB.lo"],
];

/// The channels of a film's AOVs (a film made with [`Film::with_aovs`]), written beside `R`,
/// `G`, `B` by [`write_exr_with_state`]: the mean first-hit albedo `albedo.R`, `albedo.G`,
/// `albedo.B`, shading normal `normal.X`, `normal.Y`, `normal.Z` (world space, not
/// renormalised) and depth `Z` (the OpenEXR standard depth channel: mean distance along the
/// camera ray of the samples that hit, `+∞` where none did) — the names compositors and Open
/// Image Denoise's tools take as layers `albedo`, `normal` and the depth channel.
pub const AOV_CHANNELS: [&str; 7] =
    ["albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "Z"];

/// The resume state of a film's AOVs: the eight `f64` sums of [`AovSum::to_array`], each as
/// high and low 32-bit halves (`furnace.resume.aov.<name>.hi` / `.lo`).
const AOV_STATE_NAMES: [&str; 8] =
    ["albedoR", "albedoG", "albedoB", "depth", "normalX", "normalY", "normalZ", "hits"];

/// The resume state of adaptive sampling: each pixel's sum of squared luminances (high and low
/// halves) and its convergence mark (`u32` 0 or 1).
const LUM_SQ_CHANNELS: [&str; 2] = ["furnace.resume.lumSq.hi", "furnace.resume.lumSq.lo"];
/// See [`LUM_SQ_CHANNELS`].
const CONVERGED_CHANNEL: &str = "furnace.resume.converged";

/// The 32-bit channels [`write_exr_with_state`] writes per pixel for a film with or without
/// AOVs and adaptive-sampling state: `R`, `G`, `B`, the count and the sums' halves, and those of
/// the AOVs and the adaptive state (what a render's memory plan counts for writing its EXR).
pub fn state_channel_count(aovs: bool, adaptive: bool) -> u64 {
    let image = 3 + 1 + 2 * SUM_CHANNELS.len();
    let aov = if aovs { AOV_CHANNELS.len() + 2 * AOV_STATE_NAMES.len() } else { 0 };
    let adaptive = if adaptive { LUM_SQ_CHANNELS.len() + 1 } else { 0 };
    (image + aov + adaptive) as u64
}

fn aov_state_channel(k: usize, half: &str) -> String {
    format!("{RESUME_LAYER}.aov.{}.{half}", AOV_STATE_NAMES[k])
}

/// A channel of `f32` samples written beside the image by [`write_exr_with_state_and`]
/// (e.g. `denoised.R`).
#[derive(Debug, Clone, PartialEq)]
pub struct ExtraChannel {
    /// The channel's full name (`layer.channel`).
    pub name: String,
    /// One value per pixel, row-major from the top.
    pub values: Vec<f32>,
}

/// A furnace EXR as read by [`read_exr_with_state`].
#[derive(Debug, Clone, PartialEq)]
pub struct ExrWithState {
    /// Width of the data window.
    pub width: u32,
    /// Height of the data window.
    pub height: u32,
    /// The `R`, `G`, `B` channels, row-major from the top.
    pub pixels: Vec<Vec3>,
    /// The text attributes.
    pub metadata: Metadata,
    /// The accumulation state, if the file has the [`RESUME_LAYER`] channels: the film's sums
    /// and counts, and as its rejected samples the metadata's `rejected_samples` (0 if absent).
    pub state: Option<Film>,
}

/// Writes what [`write_exr`] writes — 32-bit float `R`, `G`, `B` (the film's means,
/// [`Film::to_rgb_f32`]) and `metadata`, atomically — plus the film's accumulation state, its
/// sums (3 per pixel) and counts (1 per pixel), as the [`RESUME_LAYER`] channels, exactly. The
/// film's rejected samples are not written: record them in `metadata.rejected_samples`.
///
/// # Errors
/// As [`write_exr`]; [`PostError::FilmState`] if a count exceeds `u32::MAX`. All name `path`.
pub fn write_exr_with_state(
    path: impl AsRef<Path>,
    film: &Film,
    metadata: &Metadata,
) -> Result<(), PostError> {
    write_exr_with_state_and(path, film, metadata, &[])
}

/// [`write_exr_with_state`] with `extra` channels beside the image (a denoised image, …).
///
/// # Errors
/// As [`write_exr_with_state`]; [`PostError::FilmState`] if an extra channel does not hold
/// one value per pixel or takes a name the film's channels use.
pub fn write_exr_with_state_and(
    path: impl AsRef<Path>,
    film: &Film,
    metadata: &Metadata,
    extra: &[ExtraChannel],
) -> Result<(), PostError> {
    stage_exr_with_state_and(path, film, metadata, extra)?.commit()
}

/// What [`write_exr_with_state_and`] writes, left at its temporary name until
/// [`Staged::commit`]: for files that are replaced together or not at all (a render's EXR and
/// PNG).
///
/// # Errors
/// As [`write_exr_with_state_and`].
pub fn stage_exr_with_state_and(
    path: impl AsRef<Path>,
    film: &Film,
    metadata: &Metadata,
    extra: &[ExtraChannel],
) -> Result<Staged, PostError> {
    let path = path.as_ref();
    let (width, height) = (film.width(), film.height());
    let pixels: Vec<Vec3> = film.to_rgb_f32().chunks_exact(3).map(Vec3::from_slice).collect();
    check_size(path, width, height, pixels.len())?;
    let bad = |reason: String| PostError::FilmState { path: path.to_path_buf(), reason };
    let sums: Vec<f64> = film.sums().iter().flat_map(|s| s.to_array()).collect();
    let counts = film.counts();
    let counts: Vec<u32> = counts
        .iter()
        .map(|&c| u32::try_from(c))
        .collect::<Result<_, _>>()
        .map_err(|_| bad(format!("a pixel count exceeds {}", u32::MAX)))?;
    let mut layer_attributes = layer_attributes(path, metadata)?;
    layer_attributes.other.insert(
        Text::from_slice_unchecked(STATE_SIZE.as_bytes()),
        AttributeValue::Text(Text::from_slice_unchecked(format!("{width}x{height}").as_bytes())),
    );
    let mut list = SmallVec::new();
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let values = pixels.iter().map(|p| p[c]).collect();
        list.push(AnyChannel::new(name, FlatSamples::F32(values)));
        let bits = || sums.iter().skip(c).step_by(3).map(|s| s.to_bits());
        let [hi, lo] = SUM_CHANNELS[c];
        list.push(AnyChannel::new(hi, FlatSamples::U32(bits().map(|b| (b >> 32) as u32).collect())));
        list.push(AnyChannel::new(lo, FlatSamples::U32(bits().map(|b| b as u32).collect())));
    }
    list.push(AnyChannel::new(COUNT_CHANNEL, FlatSamples::U32(counts)));
    if let (Some(sums), Some(images)) = (film.aov_sums(), film.aov_images()) {
        let planes: [Vec<f32>; 7] = [
            images.albedo.iter().map(|v| v.x).collect(),
            images.albedo.iter().map(|v| v.y).collect(),
            images.albedo.iter().map(|v| v.z).collect(),
            images.normal.iter().map(|v| v.x).collect(),
            images.normal.iter().map(|v| v.y).collect(),
            images.normal.iter().map(|v| v.z).collect(),
            images.depth,
        ];
        for (name, values) in AOV_CHANNELS.into_iter().zip(planes) {
            list.push(AnyChannel::new(name, FlatSamples::F32(values)));
        }
        for k in 0..8 {
            let bits = || sums.iter().map(|s| s.to_array()[k].to_bits());
            list.push(AnyChannel::new(
                aov_state_channel(k, "hi").as_str(),
                FlatSamples::U32(bits().map(|b| (b >> 32) as u32).collect()),
            ));
            list.push(AnyChannel::new(
                aov_state_channel(k, "lo").as_str(),
                FlatSamples::U32(bits().map(|b| b as u32).collect()),
            ));
        }
    }
    if let (Some(lum_sq), Some(marks)) = (film.lum_sq_sums(), film.converged()) {
        let bits = || lum_sq.iter().map(|s| s.to_bits());
        list.push(AnyChannel::new(
            LUM_SQ_CHANNELS[0],
            FlatSamples::U32(bits().map(|b| (b >> 32) as u32).collect()),
        ));
        list.push(AnyChannel::new(LUM_SQ_CHANNELS[1], FlatSamples::U32(bits().map(|b| b as u32).collect())));
        list.push(AnyChannel::new(
            CONVERGED_CHANNEL,
            FlatSamples::U32(marks.iter().map(|&c| u32::from(c)).collect()),
        ));
    }
    for e in extra {
        if e.values.len() != pixels.len() {
            return Err(bad(format!(
                "channel '{}' has {} values for {} pixels",
                e.name,
                e.values.len(),
                pixels.len()
            )));
        }
        let taken = |c: &AnyChannel<FlatSamples>| c.name == Text::from_slice_unchecked(e.name.as_bytes());
        if list.iter().any(taken) {
            return Err(bad(format!("channel '{}' is written twice", e.name)));
        }
        list.push(AnyChannel::new(e.name.as_str(), FlatSamples::F32(e.values.clone())));
    }
    let size = (width as usize, height as usize);
    let layer = Layer::new(size, layer_attributes, Encoding::SMALL_LOSSLESS, AnyChannels::sort(list));
    let image = Image::from_layer(layer);
    stage_encoded(path, |out| image.write().to_buffered(out))
}

/// Reads a furnace EXR with its accumulation state: the first layer's `R`, `G`, `B` channels
/// (f16, f32 or u32, converted to f32), its text attributes, and the [`RESUME_LAYER`] channels
/// when present (`state` is `None` for files without them, such as Mitsuba's or other
/// renderers').
///
/// # Errors
/// [`PostError::Exr`] if the file cannot be read; [`PostError::FilmState`] if it lacks an
/// `R`, `G` or `B` channel, or has some but not all state channels, or one that is not `u32`;
/// [`PostError::InvalidMetadataValue`] as [`read_exr`]. All name `path`.
pub fn read_exr_with_state(path: impl AsRef<Path>) -> Result<ExrWithState, PostError> {
    let path = path.as_ref();
    let exr_err = |source| PostError::Exr { path: path.to_path_buf(), source };
    let bad = |reason: String| PostError::FilmState { path: path.to_path_buf(), reason };
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(BufReader::new(open_exr(path)?.0))
        .map_err(exr_err)?;
    let layer = &image.layer_data;
    let attributes = image.attributes.other.iter().chain(layer.attributes.other.iter());
    let metadata = Metadata::from_attributes(path, attributes)?;
    let channel = |name: &str| {
        layer.channel_data.list.iter().find(|c| c.name == Text::from_slice_unchecked(name.as_bytes()))
    };
    let n = layer.size.0 * layer.size.1;
    let mut pixels = vec![Vec3::ZERO; n];
    for (c, name) in ["R", "G", "B"].into_iter().enumerate() {
        let ch = channel(name).ok_or_else(|| bad(format!("no '{name}' channel")))?;
        for (p, v) in pixels.iter_mut().zip(ch.sample_data.values_as_f32()) {
            p[c] = v;
        }
    }
    let u32s = |name: &str| match channel(name).map(|c| &c.sample_data) {
        Some(FlatSamples::U32(v)) if v.len() == n => Ok(Some(v)),
        Some(_) => Err(bad(format!("channel '{name}' is not u32 per pixel"))),
        None => Ok(None),
    };
    let names = std::iter::once(COUNT_CHANNEL).chain(SUM_CHANNELS.into_iter().flatten());
    let found: Vec<(&str, Option<&Vec<u32>>)> =
        names.map(|name| u32s(name).map(|v| (name, v))).collect::<Result<_, _>>()?;
    let state = if found.iter().all(|(_, v)| v.is_none()) {
        None
    } else {
        if let Some((missing, _)) = found.iter().find(|(_, v)| v.is_none()) {
            return Err(bad(format!("incomplete resume state: no '{missing}' channel")));
        }
        let size_record = image
            .attributes
            .other
            .iter()
            .chain(layer.attributes.other.iter())
            .find(|(k, _)| k.bytes() == STATE_SIZE.as_bytes());
        // Files written before the record have none: their size is their data window's.
        if let Some((_, value)) = size_record {
            let recorded = match value {
                AttributeValue::Text(t) => std::str::from_utf8(t.bytes()).ok().and_then(|v| {
                    let (w, h) = v.split_once('x')?;
                    Some((w.parse::<usize>().ok()?, h.parse::<usize>().ok()?))
                }),
                _ => None,
            };
            match recorded {
                None => return Err(bad(format!("attribute '{STATE_SIZE}' is not a size WxH"))),
                Some((w, h)) if (w, h) != (layer.size.0, layer.size.1) => {
                    return Err(bad(format!(
                        "attribute '{STATE_SIZE}' records a {w}×{h} film but the data window is {}×{}: \
                         the image was cropped or resized after furnace wrote it",
                        layer.size.0, layer.size.1
                    )));
                }
                Some(_) => {}
            }
        }
        let get = |i: usize| found[i].1.map_or(&[][..], |v| v.as_slice());
        let counts = get(0).iter().map(|&c| u64::from(c)).collect();
        let mut sums = vec![DVec3::ZERO; n];
        for c in 0..3 {
            let (hi, lo) = (get(1 + 2 * c), get(2 + 2 * c));
            for (sum, (&h, &l)) in sums.iter_mut().zip(hi.iter().zip(lo)) {
                sum[c] = f64::from_bits(u64::from(h) << 32 | u64::from(l));
            }
        }
        let rejected = metadata.rejected_samples.unwrap_or(0);
        // The exr crate limits sizes to i32 range, so these fit.
        let film = Film::from_parts(layer.size.0 as u32, layer.size.1 as u32, sums, counts, rejected)
            .map_err(|e| bad(e.to_string()))?;
        // Adaptive sampling's state: all three channels or none.
        let adaptive: Vec<Option<&Vec<u32>>> = [LUM_SQ_CHANNELS[0], LUM_SQ_CHANNELS[1], CONVERGED_CHANNEL]
            .iter()
            .map(|name| u32s(name))
            .collect::<Result<_, _>>()?;
        let film = match adaptive[..] {
            [None, None, None] => film,
            [Some(hi), Some(lo), Some(marks)] => {
                let lum_sq =
                    hi.iter().zip(lo).map(|(&h, &l)| f64::from_bits(u64::from(h) << 32 | u64::from(l)));
                film.with_adaptive_state(lum_sq.collect(), marks.iter().map(|&m| m != 0).collect())
                    .map_err(|e| bad(e.to_string()))?
            }
            _ => {
                return Err(bad(
                    "incomplete adaptive-sampling state (furnace.resume.lumSq.*, .converged)".into()
                ));
            }
        };
        // The AOVs' state: all sixteen channels or none.
        let aov_names: Vec<String> =
            (0..8).flat_map(|k| [aov_state_channel(k, "hi"), aov_state_channel(k, "lo")]).collect();
        let aov: Vec<Option<&Vec<u32>>> =
            aov_names.iter().map(|name| u32s(name)).collect::<Result<_, _>>()?;
        if aov.iter().all(Option::is_none) {
            Some(film)
        } else {
            if let Some(k) = aov.iter().position(Option::is_none) {
                return Err(bad(format!("incomplete AOV state: no '{}' channel", aov_names[k])));
            }
            let halves: Vec<&Vec<u32>> = aov.into_iter().flatten().collect();
            let sums = (0..n)
                .map(|i| {
                    AovSum::from_array(std::array::from_fn(|k| {
                        f64::from_bits(u64::from(halves[2 * k][i]) << 32 | u64::from(halves[2 * k + 1][i]))
                    }))
                })
                .collect();
            Some(film.with_aov_sums(sums).map_err(|e| bad(e.to_string()))?)
        }
    };
    Ok(ExrWithState { width: layer.size.0 as u32, height: layer.size.1 as u32, pixels, metadata, state })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The count a memory plan uses is the channels written, for each kind of film.
    #[test]
    fn state_channel_count_is_what_is_written() {
        let dir = scratch("channel_count");
        for (aovs, adaptive) in [(false, false), (true, false), (false, true), (true, true)] {
            let film = if aovs { Film::with_aovs(2, 1) } else { Film::new(2, 1) };
            let film = if adaptive { film.with_adaptive() } else { film };
            let path = dir.join(format!("c{aovs}{adaptive}.exr"));
            write_exr_with_state(&path, &film, &Metadata::default()).unwrap();
            let meta = exr::meta::MetaData::read_from_file(&path, false).unwrap();
            let written = meta.headers.iter().map(|h| h.channels.list.len() as u64).sum::<u64>();
            assert_eq!(state_channel_count(aovs, adaptive), written, "aovs {aovs}, adaptive {adaptive}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("furnace-post-state-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn state_round_trips_bit_exactly_beside_rgb() {
        let dir = scratch("round_trip");
        let path = dir.join("s.exr");
        let (w, h) = (3, 2);
        // Values whose low 32 bits matter, signed zero, a subnormal, the largest finite, NaN
        // with a payload: every bit of every sum must survive.
        let mut sums = vec![
            0.1,
            -0.0,
            f64::MIN_POSITIVE / 3.0,
            f64::MAX,
            f64::from_bits(0x7ff8_0000_dead_beef),
            1.0 + f64::EPSILON,
        ];
        sums.extend((0..12).map(|i| (i as f64).sqrt() * 1e10 + 1e-7));
        let counts = vec![0, 1, 7, u64::from(u32::MAX), 123_456, 42];
        let film =
            Film::from_parts(w, h, sums.chunks_exact(3).map(DVec3::from_slice).collect(), counts.clone(), 5)
                .unwrap();
        let meta = Metadata {
            spp: Some(7),
            scene: Some("x".into()),
            rejected_samples: Some(5),
            ..Metadata::default()
        };
        write_exr_with_state(&path, &film, &meta).unwrap();

        let back = read_exr_with_state(&path).unwrap();
        assert_eq!((back.width, back.height), (w, h));
        let f32_bits = |v: &[f32]| v.iter().map(|s| s.to_bits()).collect::<Vec<_>>();
        let rgb: Vec<f32> = back.pixels.iter().flat_map(|p| p.to_array()).collect();
        assert_eq!(f32_bits(&rgb), f32_bits(&film.to_rgb_f32()), "R, G, B are the film's means");
        assert_eq!(back.metadata, meta);
        let state = back.state.expect("the state channels were written");
        let bits =
            |f: &Film| f.sums().iter().flat_map(|s| s.to_array().map(f64::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&state), bits(&film));
        assert_eq!(state.counts(), &counts[..]);
        assert_eq!(state.rejected(), 5, "from the metadata");

        // Readers that only want the image still see R, G, B.
        let (rw, rh, rgb2, m) = read_exr(&path).unwrap();
        assert_eq!((rw, rh, m), (w, h, meta));
        assert_eq!(f32_bits(&rgb2.iter().flat_map(|p| p.to_array()).collect::<Vec<_>>()), f32_bits(&rgb));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn aovs_and_extra_channels_round_trip() {
        let dir = scratch("aovs");
        let path = dir.join("a.exr");
        let mut film = Film::with_aovs(2, 1);
        let hit = furnace_render::AovSample {
            albedo: Vec3::new(0.1, 0.2, 0.3),
            normal: Vec3::new(0.0, 0.6, 0.8),
            depth: Some(2.5),
        };
        film.add_sample_with_aovs(0, 0, Vec3::ONE, &hit);
        film.add_sample_with_aovs(0, 0, Vec3::ONE, &furnace_render::AovSample::MISS);
        film.add_sample_with_aovs(1, 0, Vec3::ONE, &furnace_render::AovSample::MISS);
        let extra = [ExtraChannel { name: "denoised.R".into(), values: vec![0.5, 0.25] }];
        write_exr_with_state_and(&path, &film, &Metadata::default(), &extra).unwrap();
        let back = read_exr_with_state(&path).unwrap();
        assert_eq!(back.state.as_ref().unwrap().aov_sums(), film.aov_sums(), "AOV sums bit for bit");
        // The AOV layers hold the means: what compositors and denoisers read.
        let image = read()
            .no_deep_data()
            .largest_resolution_level()
            .all_channels()
            .first_valid_layer()
            .all_attributes()
            .from_file(&path)
            .unwrap();
        let channel = |name: &str| -> Vec<f32> {
            let c = image.layer_data.channel_data.list.iter().find(|c| c.name == *name);
            c.unwrap_or_else(|| panic!("no channel {name}")).sample_data.values_as_f32().collect()
        };
        assert_eq!(channel("albedo.R"), [0.55, 1.0]);
        assert_eq!(channel("normal.Z"), [0.4, 0.0]);
        assert_eq!(channel("Z"), [2.5, f32::INFINITY]);
        assert_eq!(channel("denoised.R"), [0.5, 0.25]);
        // An extra channel of the wrong length, or a name already used, writes nothing.
        let path2 = dir.join("b.exr");
        let short = [ExtraChannel { name: "x".into(), values: vec![1.0] }];
        assert!(write_exr_with_state_and(&path2, &film, &Metadata::default(), &short).is_err());
        let twice = [ExtraChannel { name: "Z".into(), values: vec![1.0, 2.0] }];
        let e = write_exr_with_state_and(&path2, &film, &Metadata::default(), &twice).unwrap_err();
        assert!(e.to_string().contains("'Z' is written twice"), "{e}");
        assert!(!path2.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn adaptive_state_round_trips() {
        let dir = scratch("adaptive");
        let path = dir.join("a.exr");
        let mut film = Film::new(3, 1).with_adaptive();
        for (x, v) in [(0, 0.5), (0, 1.5), (1, 2.0), (1, 2.0), (2, 0.1)] {
            film.add_sample(x, 0, Vec3::splat(v));
        }
        film.test_convergence(&furnace_render::AdaptiveSampling { threshold: 0.1, min_samples: 2 });
        assert_eq!(film.converged(), Some(&[false, true, false][..]));
        write_exr_with_state(&path, &film, &Metadata::default()).unwrap();
        let back = read_exr_with_state(&path).unwrap().state.unwrap();
        assert_eq!(back.converged(), film.converged());
        let bits = |f: &Film| f.lum_sq_sums().unwrap().iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back), bits(&film));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn files_without_state_read_as_none() {
        let dir = scratch("none");
        let path = dir.join("plain.exr");
        let pixels = vec![Vec3::new(1.0, 2.0, 3.0); 4];
        write_exr(&path, 2, 2, &pixels, &Metadata::default()).unwrap();
        let back = read_exr_with_state(&path).unwrap();
        assert_eq!((back.pixels, back.state), (pixels, None));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn bad_state_is_an_error_naming_the_file() {
        let dir = scratch("bad");
        let path = dir.join("bad.exr");
        let film = Film::from_parts(2, 1, vec![DVec3::ZERO; 2], vec![1 << 32, 0], 0).unwrap();
        let big = write_exr_with_state(&path, &film, &Metadata::default()).unwrap_err();
        assert!(matches!(big, PostError::FilmState { .. }), "{big}");
        assert!(big.to_string().contains("bad.exr") && big.to_string().contains("exceeds"), "{big}");
        assert!(!path.exists());
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
