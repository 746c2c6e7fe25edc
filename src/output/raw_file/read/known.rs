//! The variables a reader knows: each one's dimensions, value class and the values it
//! must hold, by format version; the shapes any other dataset may have.

use std::path::Path;

use hdf5::Dataset;
use hdf5::types::TypeDescriptor;
use ndarray::{Ix1, s};

/// Values of a per-profile variable read at once while checking them.
pub const SCAN_BLOCK: usize = 1 << 16;
use crate::error::{Error, Result};

use super::super::spec::{
    BIN_DIM, CHANNEL_DIM, CHANNEL_NAME, COLUMN_DIM, COMPONENT_NAMES, PROFILE_COLUMN_NAMES,
    PROFILE_DIM, SLOT_DIM,
};

/// The type of a dataset's values, as far as the layout cares.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Class {
    Unsigned,
    Signed,
    Float,
    Text,
    Other,
}

impl Class {
    pub(super) fn of(d: &Dataset) -> (Class, usize) {
        let Some(t) = d.dtype().ok().and_then(|t| t.to_descriptor().ok()) else {
            return (Class::Other, 0);
        };
        let size = t.size();
        let class = match t {
            TypeDescriptor::Unsigned(_) => Class::Unsigned,
            TypeDescriptor::Integer(_) => Class::Signed,
            TypeDescriptor::Float(_) => Class::Float,
            TypeDescriptor::VarLenUnicode
            | TypeDescriptor::VarLenAscii
            | TypeDescriptor::FixedAscii(_)
            | TypeDescriptor::FixedUnicode(_) => Class::Text,
            _ => Class::Other,
        };
        (class, size)
    }

    pub(super) fn name(self) -> &'static str {
        match self {
            Class::Unsigned => "unsigned integers",
            Class::Signed => "signed integers",
            Class::Float => "floating-point numbers",
            Class::Text => "strings",
            Class::Other => "another type",
        }
    }
}

/// A dimension of the layout.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Dim {
    P,
    C,
    B,
    /// The scene's distinct columns (format 3), the length of `column`.
    Col,
    /// A profile's column slots (format 3), the length of `k`.
    K,
}

/// What [`check`] asks of a value of a variable.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Values {
    /// Nothing beyond its type.
    Any,
    /// Finite.
    Finite,
    /// Finite and ≥ 0.
    NonNegative,
    /// ≥ 1 (an unsigned count).
    AtLeastOne,
}

/// A variable of the layout: name, dimensions, type, whether every file has it, and
/// what its values must be.
pub(super) struct Known {
    pub(super) name: &'static str,
    pub(super) dims: &'static [Dim],
    pub(super) class: Class,
    pub(super) required: bool,
    pub(super) values: Values,
}

pub(super) const fn known(
    name: &'static str,
    dims: &'static [Dim],
    class: Class,
    required: bool,
    values: Values,
) -> Known {
    Known {
        name,
        dims,
        class,
        required,
        values,
    }
}

/// A string variable of the channel dimension (format 3).
pub(super) const fn channel_text(name: &'static str) -> Known {
    known(name, &[Dim::C], Class::Text, false, Values::Any)
}

/// The variables of the layout [`check`] knows by name (docs/file-format.md).
pub(super) const KNOWN: [Known; 28] = [
    known(COLUMN_DIM, &[Dim::Col], Class::Signed, false, Values::Any),
    known(SLOT_DIM, &[Dim::K], Class::Signed, false, Values::Any),
    known(
        PROFILE_COLUMN_NAMES[0],
        &[Dim::P, Dim::K],
        Class::Signed,
        false,
        Values::Any,
    ),
    known(
        PROFILE_COLUMN_NAMES[1],
        &[Dim::P, Dim::K],
        Class::Float,
        false,
        Values::Any,
    ),
    channel_text(CHANNEL_NAME),
    channel_text("channel_kind"),
    channel_text("channel_species"),
    channel_text("polarization"),
    channel_text("detection_mode"),
    channel_text("acquisition_mode"),
    channel_text("glue_partner"),
    channel_text("dead_time_model"),
    channel_text("molecular_line"),
    known(
        "counts",
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        true,
        Values::Any,
    ),
    known(
        COMPONENT_NAMES[0],
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        false,
        Values::Any,
    ),
    known(
        COMPONENT_NAMES[1],
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        false,
        Values::Any,
    ),
    known(
        COMPONENT_NAMES[2],
        &[Dim::P, Dim::C, Dim::B],
        Class::Unsigned,
        false,
        Values::Any,
    ),
    // the names before format 5, the numbers from it (`check`)
    known(CHANNEL_DIM, &[Dim::C], Class::Text, true, Values::Any),
    known(PROFILE_DIM, &[Dim::P], Class::Signed, false, Values::Any),
    known(BIN_DIM, &[Dim::B], Class::Signed, false, Values::Any),
    known("time", &[Dim::P], Class::Float, true, Values::Finite),
    known(
        "n_shots",
        &[Dim::P],
        Class::Unsigned,
        true,
        Values::AtLeastOne,
    ),
    known(
        "pulse_energy",
        &[Dim::P],
        Class::Float,
        true,
        Values::NonNegative,
    ),
    known("latitude", &[Dim::P], Class::Float, false, Values::Finite),
    known("longitude", &[Dim::P], Class::Float, false, Values::Finite),
    known(
        "along_track_distance",
        &[Dim::P],
        Class::Float,
        false,
        Values::Finite,
    ),
    known("altitude", &[Dim::B], Class::Float, true, Values::Finite),
    known("range", &[Dim::B], Class::Float, true, Values::Finite),
];

/// The shapes any other dataset of a raw file may have.
pub(super) const OTHER_SHAPES: [&[Dim]; 8] = [
    &[Dim::P],
    &[Dim::P, Dim::C],
    &[Dim::C],
    &[Dim::B],
    &[Dim::C, Dim::B],
    &[Dim::P, Dim::C, Dim::B],
    &[Dim::Col, Dim::B],
    &[Dim::Col, Dim::C, Dim::B],
];

pub(super) fn dims_name(dims: &[Dim]) -> String {
    let names: Vec<&str> = dims
        .iter()
        .map(|d| match d {
            Dim::P => PROFILE_DIM,
            Dim::C => CHANNEL_DIM,
            Dim::B => BIN_DIM,
            Dim::Col => COLUMN_DIM,
            Dim::K => SLOT_DIM,
        })
        .collect();
    format!("({})", names.join(", "))
}

/// Checks the values of variable `name` (dataset `d`), [`SCAN_BLOCK`] at a time.
pub(super) fn scan(path: &Path, name: &str, values: Values, d: &Dataset) -> Result<()> {
    let n = d.shape().first().copied().unwrap_or(0);
    let unreadable = |e: hdf5::Error| {
        Error::output(
            path,
            format!(
                "cannot read `{}`: {}",
                name,
                crate::error::describe_hdf5_error(&e.to_string())
            ),
        )
    };
    for a in (0..n).step_by(SCAN_BLOCK) {
        let b = (a + SCAN_BLOCK).min(n);
        let bad_at = |i: usize, v: String, want: &str| {
            Error::output(path, format!("`{}` value {} is {v}; {want}", name, a + i))
        };
        match values {
            Values::Any => {}
            Values::AtLeastOne => {
                let v = d.read_slice::<u64, _, Ix1>(s![a..b]).map_err(unreadable)?;
                if let Some(i) = v.iter().position(|&x| x < 1) {
                    return Err(bad_at(
                        i,
                        v[i].to_string(),
                        "every profile accumulates at least one shot",
                    ));
                }
            }
            Values::Finite | Values::NonNegative if d.ndim() == 2 => {
                let v = d
                    .read_slice::<f64, _, ndarray::Ix2>(s![a..b, ..])
                    .map_err(unreadable)?;
                let ok = |x: f64| x.is_finite() && (values == Values::Finite || x >= 0.0);
                if let Some(((i, j), x)) = v.indexed_iter().find(|(_, x)| !ok(**x)) {
                    return Err(Error::output(
                        path,
                        format!(
                            "`{name}` value ({}, {j}) is {x}; it must be finite{}",
                            a + i,
                            if values == Values::Finite {
                                ""
                            } else {
                                " and not negative"
                            }
                        ),
                    ));
                }
            }
            Values::Finite | Values::NonNegative => {
                let v = d.read_slice::<f64, _, Ix1>(s![a..b]).map_err(unreadable)?;
                let ok = |x: f64| x.is_finite() && (values == Values::Finite || x >= 0.0);
                if let Some(i) = v.iter().position(|&x| !ok(x)) {
                    let want = match values {
                        Values::Finite => "it must be finite",
                        _ => "it must be finite and not negative",
                    };
                    return Err(bad_at(i, v[i].to_string(), want));
                }
            }
        }
    }
    Ok(())
}
