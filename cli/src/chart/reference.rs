//! A reference image and the BRDF model it was rendered with (recorded by furnace, or
//! declared on the command line).

use crate::args::Switch;
use crate::resume;
use clap::ValueEnum;
use furnace_brdf::Masking;
use furnace_render::Choice;
use glam::Vec3;
use serde_json::{Value, json};
use std::path::{Path, PathBuf};

/// A reference image and the model it was rendered with.
pub(super) struct Reference {
    pub(super) path: PathBuf,
    pub(super) width: u32,
    pub(super) height: u32,
    pub(super) pixels: Vec<Vec3>,
    /// 16 hex digits of a hash of the pixels (the study records it).
    pub(super) hash: String,
    pub(super) compensation: Switch,
    /// The masking it records (a furnace render), `None` when unknown.
    pub(super) masking: Option<Masking>,
    pub(super) metadata: furnace_post::Metadata,
    /// Whether furnace wrote it (it carries `furnace.scene_hash`).
    pub(super) furnace: bool,
}

impl Reference {
    pub(super) fn load(path: &Path, declared: Option<Switch>, default: Switch) -> Result<Self, String> {
        let (width, height, pixels, metadata) = furnace_post::read_exr(path).map_err(|e| e.to_string())?;
        let p = path.display();
        let recorded = |key: &str| metadata.extra.get(key).map(String::as_str);
        let furnace = recorded(resume::SCENE_HASH).is_some();
        let compensation = match recorded(resume::key("compensation")) {
            Some(v) => {
                let c = Switch::from_str(v, false).map_err(|_| format!("{p}: unknown compensation '{v}'"))?;
                if let Some(d) = declared.filter(|&d| d != c) {
                    return Err(format!(
                        "{p} records --compensation {v}, but --reference-compensation says {}",
                        resume::cli_name(&d)
                    ));
                }
                c
            }
            None => declared.unwrap_or(default),
        };
        let masking = recorded(resume::key("masking"))
            .map(|v| Masking::from_name(v).ok_or_else(|| format!("{p}: unknown masking '{v}'")))
            .transpose()?;
        Ok(Self {
            path: path.to_path_buf(),
            width,
            height,
            hash: pixels_hash(&pixels),
            pixels,
            compensation,
            masking,
            metadata,
            furnace,
        })
    }

    pub(super) fn settings(&self) -> Value {
        json!({
            "pixels_hash": self.hash,
            "compensation": resume::cli_name(&self.compensation),
            "masking": self.masking.map(Choice::name),
        })
    }

    pub(super) fn name(&self) -> String {
        self.path
            .file_name()
            .map_or_else(|| self.path.display().to_string(), |n| n.to_string_lossy().into_owned())
    }
}

/// 16 hex digits of FNV-1a over the pixels' f32 bits.
fn pixels_hash(pixels: &[Vec3]) -> String {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    for v in pixels.iter().flat_map(|v| v.to_array()) {
        // FNV-1a over the f32 bits.
        for b in v.to_bits().to_le_bytes() {
            h = (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    format!("{h:016x}")
}
