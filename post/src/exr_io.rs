//! Linear RGB OpenEXR output and input through the `exr` crate, with render metadata stored as
//! text attributes.

use crate::PostError;
use crate::atomic::write_atomic;
use exr::prelude::{
    AttributeValue, Encoding, Image, Layer, LayerAttributes, ReadChannels, ReadLayers, SpecificChannels,
    Text, Vec2, WritableImage, read,
};
use glam::Vec3;
use std::collections::{BTreeMap, HashMap};
use std::io::{BufWriter, Write};
use std::path::Path;

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
const FURNACE_KEYS: [&str; 7] = [SPP, SAMPLER, BOUNCES, SEED, SCENE, RENDER_TIME, REJECTED];

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
    let attributes = metadata.to_attributes(path)?;
    let mut other = HashMap::new();
    for (k, v) in attributes {
        other.insert(
            Text::from_slice_unchecked(k.as_bytes()),
            AttributeValue::Text(Text::from_slice_unchecked(v.as_bytes())),
        );
    }
    let layer_attributes = LayerAttributes { other, ..LayerAttributes::default() };
    let w = width as usize;
    let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
        let p = pixels[y * w + x];
        (p.x, p.y, p.z)
    });
    let layer = Layer::new((w, height as usize), layer_attributes, Encoding::SMALL_LOSSLESS, channels);
    let image = Image::from_layer(layer);
    let exr_err = |source| PostError::Exr { path: path.to_path_buf(), source };
    write_atomic(path, |file| {
        let mut out = BufWriter::new(file);
        image.write().to_buffered(&mut out).map_err(exr_err)?;
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
        .from_file(path)
        .map_err(exr_err)?;
    let layer = &image.layer_data;
    let size = layer.size;
    let attributes = image.attributes.other.iter().chain(layer.attributes.other.iter());
    let metadata = Metadata::from_attributes(path, attributes)?;
    let (_, pixels) = &layer.channel_data.pixels;
    // The exr crate limits sizes to i32 range, so these fit.
    Ok((size.0 as u32, size.1 as u32, pixels.clone(), metadata))
}
