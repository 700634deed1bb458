//! [`Choice`]: a setting that takes one of a few named values, with the names and one line of
//! help for each, so that the command line, the viewer's panel, the EXR record and the resume
//! check spell them alike.

use furnace_brdf::{Masking, SpecularSampling};

/// A setting's value among named alternatives.
pub trait Choice: Copy + PartialEq + Send + Sync + 'static {
    /// Every value, in command-line order.
    const VALUES: &'static [Self];

    /// The name: on the command line, in the EXR record and in messages (`solid-angle`).
    fn name(self) -> &'static str;

    /// One line saying what the value does (the command line's help of the value).
    fn help(self) -> &'static str;

    /// The value named exactly `name` (the names are case-sensitive, as the command line's).
    fn from_name(name: &str) -> Option<Self> {
        Self::VALUES.iter().copied().find(|v| v.name() == name)
    }
}

/// Every value of `T` as `(name, help)` pairs, in command-line order.
pub fn choices<T: Choice>() -> Vec<(&'static str, &'static str)> {
    T::VALUES.iter().map(|v| (v.name(), v.help())).collect()
}

/// The values of an on/off switch (`compensation`, `russian-roulette`): `(name, help)` pairs.
pub fn on_off() -> Vec<(&'static str, &'static str)> {
    vec![("on", "Enabled"), ("off", "Disabled")]
}

/// `on` or `off`.
pub fn on_off_name(on: bool) -> &'static str {
    if on { "on" } else { "off" }
}

/// `true` for `on`, `false` for `off`.
///
/// # Errors
/// Any other text, with what is accepted.
pub fn parse_on_off(s: &str) -> Result<bool, String> {
    match s {
        "on" => Ok(true),
        "off" => Ok(false),
        _ => Err(format!("'{s}' is not on or off")),
    }
}

/// The value of `T` named `s`.
///
/// # Errors
/// An unknown name, with the names accepted.
pub fn parse_choice<T: Choice>(s: &str) -> Result<T, String> {
    T::from_name(s).ok_or_else(|| {
        let names: Vec<&str> = T::VALUES.iter().map(|v| v.name()).collect();
        format!("'{s}' is not one of {}", names.join(", "))
    })
}

/// Implements [`Choice`] from the type's `ALL` and `name()` and the help of each value.
macro_rules! impl_choice {
    ($ty:ty { $($value:ident => $help:literal),+ $(,)? }) => {
        impl $crate::Choice for $ty {
            const VALUES: &'static [Self] = &<$ty>::ALL;

            fn name(self) -> &'static str {
                <$ty>::name(self)
            }

            fn help(self) -> &'static str {
                match self {
                    $(Self::$value => $help,)+
                }
            }
        }
    };
}

pub(crate) use impl_choice;

impl Choice for Masking {
    const VALUES: &'static [Self] = &[Masking::Separable, Masking::HeightCorrelated];

    fn name(self) -> &'static str {
        match self {
            Masking::Separable => "separable",
            Masking::HeightCorrelated => "height-correlated",
        }
    }

    fn help(self) -> &'static str {
        match self {
            Masking::Separable => "G1(ωo)·G1(ωi) (the thesis, Mitsuba 3)",
            Masking::HeightCorrelated => "1/(1 + Λ(ωo) + Λ(ωi)) (glTF, pbrt-v4)",
        }
    }
}

impl Choice for SpecularSampling {
    const VALUES: &'static [Self] =
        &[SpecularSampling::Ndf, SpecularSampling::Vndf, SpecularSampling::SphericalCaps];

    fn name(self) -> &'static str {
        match self {
            SpecularSampling::Ndf => "ndf",
            SpecularSampling::Vndf => "vndf",
            SpecularSampling::SphericalCaps => "caps",
        }
    }

    fn help(self) -> &'static str {
        match self {
            SpecularSampling::Ndf => "The distribution of normals (the thesis)",
            SpecularSampling::Vndf => "Visible normals (Heitz 2018)",
            SpecularSampling::SphericalCaps => "Visible normals by spherical caps (Dupuy & Benyoub 2023)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{EnvSampling, LightSampling, LightSelection, PointLightSampling, TriangleSampling};

    fn round_trip<T: Choice + std::fmt::Debug>() {
        for &v in T::VALUES {
            assert_eq!(T::from_name(v.name()), Some(v));
            assert!(!v.help().is_empty());
        }
        assert_eq!(T::from_name("no such value"), None);
    }

    #[test]
    fn every_choice_parses_its_names_exactly() {
        round_trip::<LightSampling>();
        round_trip::<TriangleSampling>();
        round_trip::<LightSelection>();
        round_trip::<PointLightSampling>();
        round_trip::<EnvSampling>();
        round_trip::<Masking>();
        round_trip::<SpecularSampling>();
        assert_eq!(LightSampling::from_name("MIS"), None, "case-sensitive, as the command line");
        assert_eq!(parse_choice::<SpecularSampling>("x"), Err("'x' is not one of ndf, vndf, caps".into()));
        assert_eq!((parse_on_off("on"), parse_on_off("off")), (Ok(true), Ok(false)));
        assert!(parse_on_off("yes").is_err());
    }
}
