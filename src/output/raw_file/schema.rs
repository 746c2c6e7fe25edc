//! The raw file's variables as data: for each, its name, dimensions, element type,
//! attributes in the order they are written, and the values known before the first
//! profile. One description for the two forms of a run: `layout` creates
//! exactly these in an HDF5 file, `memory` holds exactly these in memory (the
//! Python module's in-memory `simulate`, docs/python.md), so that both have the same
//! variables, dimensions and CF attributes.

use super::spec::{
    AttrValue, BIN_DIM, CHANNEL_DIM, CHANNEL_NAME, COLUMN_DIM, COMPONENT_NAMES, CountWidth, Dims,
    PROFILE_COLUMN_NAMES, PROFILE_DIM, RawFileSpec, SLOT_DIM,
};

/// The auxiliary coordinates of (profile, channel, bin) and (bin) data variables.
const COORDS_PROFILE_BIN: &str = "time altitude range";
const COORDS_BIN: &str = "altitude range";

/// The element type of a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Element {
    /// i64: an index coordinate (`profile`, `bin`, `column`, `k`).
    I64,
    /// A variable-length UTF-8 string.
    Text,
    /// Unsigned counts of the file's [`CountWidth`].
    Count(CountWidth),
    F64,
    U64,
    I32,
}

/// Which per-profile field of a [`super::spec::ProfileRecord`] fills a variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PerProfile {
    /// A (profile, channel, bin) row: `counts`, a component, or the spec's
    /// (profile, channel, bin) variable; rows come in this order
    /// (`RecordShape::split` in `check`).
    Row,
    /// `time`: [`super::spec::ProfileRecord::time_s`].
    Time,
    /// `n_shots`.
    NShots,
    /// `pulse_energy`.
    PulseEnergy,
    /// The spec's (profile) or (profile, channel) variable: one row of
    /// [`super::spec::ProfileRecord::values`].
    Value,
    /// `profile_column`.
    Columns,
    /// `profile_column_weight`.
    ColumnWeights,
}

/// A variable's values: known up front, or filled profile by profile.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Values<'a> {
    /// `first, first + 1, …` along the variable's one dimension.
    Index { first: usize },
    /// One string per element.
    Text(&'a [String]),
    /// Row-major values of the whole shape.
    F64(&'a [f64]),
    /// Filled by the profiles.
    PerProfile(PerProfile),
    /// A (column, …) variable of a scene whose columns come one by one
    /// ([`RawFileSpec::streamed_columns`]).
    Streamed,
}

/// How HDF5 stores a variable (the in-memory form ignores it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Storage {
    /// Contiguous, written once.
    Contiguous,
    /// Chunked along profiles, shuffled and deflated, filled by the writer a chunk at a
    /// time; `by_planes`: a count variable, its chunks encoded byte plane by byte plane.
    Rows { by_planes: bool },
    /// Chunked along columns, shuffled and deflated (most of a scene's truth repeats).
    Deflated,
}

/// One variable of the raw file.
#[derive(Clone, Debug, PartialEq)]
pub struct VarSchema<'a> {
    /// Name in the file.
    pub name: &'a str,
    /// Dimension names, outermost first.
    pub dims: Vec<&'static str>,
    /// Length of each dimension.
    pub shape: Vec<usize>,
    pub element: Element,
    pub values: Values<'a>,
    pub storage: Storage,
    /// Attributes in the order they are written.
    pub attributes: Vec<(String, AttrValue)>,
    /// A dimension's own coordinate (an HDF5 dimension scale named as the dimension).
    pub is_dimension: bool,
}

impl VarSchema<'_> {
    /// Elements of the whole variable.
    pub fn len(&self) -> usize {
        self.shape.iter().product()
    }

    /// Whether the variable holds no element.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Text attributes.
fn text(attrs: &[(&str, &str)]) -> Vec<(String, AttrValue)> {
    attrs
        .iter()
        .map(|(k, v)| (k.to_string(), AttrValue::Str(v.to_string())))
        .collect()
}

/// A dimension's index coordinate, `first..first + n`.
fn index<'a>(name: &'static str, n: usize, first: usize, long_name: &str) -> VarSchema<'a> {
    VarSchema {
        name,
        dims: vec![name],
        shape: vec![n],
        element: Element::I64,
        values: Values::Index { first },
        storage: Storage::Contiguous,
        attributes: text(&[("long_name", long_name), ("units", "1")]),
        is_dimension: true,
    }
}

/// Every variable of `spec`'s file, in the order the file creates them.
pub fn schema(spec: &RawFileSpec) -> Vec<VarSchema<'_>> {
    let (p, c, b) = (spec.n_profiles, spec.channels.len(), spec.n_bins);
    // the coordinates of (profile, …) variables: time, and latitude/longitude where given
    let extra: String = spec
        .profile_coordinates
        .iter()
        .map(|c| format!(" {c}"))
        .collect();
    let coords_profile_bin = format!("{COORDS_PROFILE_BIN}{extra}");
    let coords_profile = format!("time{extra}");
    let profile_bin = |name, element, per: PerProfile, storage, attrs: Vec<_>| VarSchema {
        name,
        dims: vec![PROFILE_DIM, CHANNEL_DIM, BIN_DIM],
        shape: vec![p, c, b],
        element,
        values: Values::PerProfile(per),
        storage,
        attributes: attrs,
        is_dimension: false,
    };
    let profile_var = |name, element, per, attrs: Vec<_>| VarSchema {
        name,
        dims: vec![PROFILE_DIM],
        shape: vec![p],
        element,
        values: Values::PerProfile(per),
        storage: Storage::Contiguous,
        attributes: attrs,
        is_dimension: false,
    };

    let mut vars = vec![
        index(PROFILE_DIM, p, spec.first_profile, "profile index"),
        index(CHANNEL_DIM, c, 0, "receiver channel number"),
        index(BIN_DIM, b, 0, "range bin index"),
        VarSchema {
            name: CHANNEL_NAME,
            dims: vec![CHANNEL_DIM],
            shape: vec![c],
            element: Element::Text,
            values: Values::Text(&spec.channels),
            storage: Storage::Contiguous,
            attributes: text(&[("long_name", "receiver channel name")]),
            is_dimension: false,
        },
    ];
    vars.extend(spec.channel_text.iter().map(|t| VarSchema {
        name: &t.name,
        dims: vec![CHANNEL_DIM],
        shape: vec![c],
        element: Element::Text,
        values: Values::Text(&t.values),
        storage: Storage::Contiguous,
        attributes: text(&[("long_name", &t.long_name)]),
        is_dimension: false,
    }));
    if spec.n_columns > 0 {
        let long_name = "distinct column of the scene (segment and cloud cells present)";
        vars.push(index(COLUMN_DIM, spec.n_columns, 0, long_name));
    }
    if spec.column_slots > 0 {
        let k = spec.column_slots;
        vars.push(index(SLOT_DIM, k, 0, "slot of a profile's columns"));
        let slots = |name, element, per, long_name: &str| VarSchema {
            name,
            dims: vec![PROFILE_DIM, SLOT_DIM],
            shape: vec![p, k],
            element,
            values: Values::PerProfile(per),
            storage: Storage::Contiguous,
            attributes: text(&[
                ("long_name", long_name),
                ("units", "1"),
                ("coordinates", &coords_profile),
            ]),
            is_dimension: false,
        };
        vars.push(slots(
            PROFILE_COLUMN_NAMES[0],
            Element::I32,
            PerProfile::Columns,
            "columns the profile's shots saw (index of the column dimension; -1 = unused slot)",
        ));
        vars.push(slots(
            PROFILE_COLUMN_NAMES[1],
            Element::F64,
            PerProfile::ColumnWeights,
            "share of the profile's shots that saw the column (sums to 1 over k)",
        ));
    }

    let counts = Element::Count(spec.count_width);
    let by_planes = Storage::Rows { by_planes: true };
    let count_attrs = |long_name: &str| {
        text(&[
            ("long_name", long_name),
            ("units", "count"),
            ("coordinates", &coords_profile_bin),
        ])
    };
    vars.push(profile_bin(
        "counts",
        counts,
        PerProfile::Row,
        by_planes,
        count_attrs("accumulated raw photon counts (signal + background + dark)"),
    ));
    if spec.components {
        let long_names = [
            "accumulated photon counts from the backscattered laser signal",
            "accumulated photon counts from the sky background",
            "accumulated detector dark counts",
        ];
        for (name, long_name) in COMPONENT_NAMES.into_iter().zip(long_names) {
            vars.push(profile_bin(
                name,
                counts,
                PerProfile::Row,
                by_planes,
                count_attrs(long_name),
            ));
        }
    }
    vars.push(profile_var(
        "time",
        Element::F64,
        PerProfile::Time,
        text(&[
            ("long_name", "profile centre time"),
            ("standard_name", "time"),
            ("units", &spec.time_units),
            ("calendar", "standard"),
            ("axis", "T"),
        ]),
    ));
    vars.push(profile_var(
        "n_shots",
        Element::U64,
        PerProfile::NShots,
        text(&[
            ("long_name", "laser shots accumulated in the profile"),
            ("units", "1"),
            ("coordinates", &coords_profile),
        ]),
    ));
    vars.push(VarSchema {
        dims: vec![PROFILE_DIM, CHANNEL_DIM],
        shape: vec![p, c],
        ..profile_var(
            "pulse_energy",
            Element::F64,
            PerProfile::PulseEnergy,
            text(&[
                (
                    "long_name",
                    "mean emitted pulse energy of the profile's shots at the channel's laser line (energy monitor)",
                ),
                ("units", "J"),
                ("coordinates", &coords_profile),
            ]),
        )
    });

    for var in &spec.variables {
        let (n, coords_profile_bin, coords_profile) =
            (spec.n_columns, &*coords_profile_bin, &*coords_profile);
        let (dims, shape, coords): (Vec<&'static str>, Vec<usize>, Option<&str>) = match var.dims {
            Dims::Bin => (vec![BIN_DIM], vec![b], Some(COORDS_BIN)),
            Dims::Channel => (vec![CHANNEL_DIM], vec![c], None),
            Dims::ChannelBin => (vec![CHANNEL_DIM, BIN_DIM], vec![c, b], Some(COORDS_BIN)),
            Dims::Profile => (vec![PROFILE_DIM], vec![p], Some(coords_profile)),
            Dims::ProfileChannel => (
                vec![PROFILE_DIM, CHANNEL_DIM],
                vec![p, c],
                Some(coords_profile),
            ),
            Dims::ProfileChannelBin => (
                vec![PROFILE_DIM, CHANNEL_DIM, BIN_DIM],
                vec![p, c, b],
                Some(coords_profile_bin),
            ),
            Dims::ColumnBin => (vec![COLUMN_DIM, BIN_DIM], vec![n, b], Some(COORDS_BIN)),
            Dims::ColumnChannelBin => (
                vec![COLUMN_DIM, CHANNEL_DIM, BIN_DIM],
                vec![n, c, b],
                Some(COORDS_BIN),
            ),
        };
        let (values, storage) = match var.dims {
            Dims::ProfileChannelBin => (
                Values::PerProfile(PerProfile::Row),
                Storage::Rows { by_planes: false },
            ),
            Dims::Profile | Dims::ProfileChannel => {
                (Values::PerProfile(PerProfile::Value), Storage::Contiguous)
            }
            Dims::ColumnBin | Dims::ColumnChannelBin if spec.streamed_columns => {
                (Values::Streamed, Storage::Deflated)
            }
            Dims::ColumnBin | Dims::ColumnChannelBin => (Values::F64(&var.data), Storage::Deflated),
            _ => (Values::F64(&var.data), Storage::Contiguous),
        };
        let mut attributes = text(&[("long_name", &var.long_name), ("units", &var.units)]);
        attributes.extend(var.attributes.iter().cloned());
        // a coordinate itself (altitude, range, latitude, ...) lists no coordinates
        let is_coordinate = matches!(var.name.as_str(), "altitude" | "range")
            || spec.profile_coordinates.contains(&var.name);
        if let Some(coords) = coords.filter(|_| !is_coordinate) {
            attributes.push(("coordinates".into(), AttrValue::Str(coords.into())));
        }
        vars.push(VarSchema {
            name: &var.name,
            dims,
            shape,
            element: Element::F64,
            values,
            storage,
            attributes,
            is_dimension: false,
        });
    }
    label_channels(&mut vars);
    vars
}

/// Lists the channels' names, `channel_name`, in the `coordinates` attribute of every
/// variable with the channel dimension (CF §6.1: the names label the numbered channels).
pub(super) fn label_channels(vars: &mut [VarSchema]) {
    for v in vars.iter_mut() {
        if v.name == CHANNEL_NAME || v.is_dimension || !v.dims.contains(&CHANNEL_DIM) {
            continue;
        }
        match v.attributes.iter_mut().find(|(k, _)| k == "coordinates") {
            Some((_, AttrValue::Str(c))) => c.push_str(&format!(" {CHANNEL_NAME}")),
            _ => v
                .attributes
                .push(("coordinates".into(), AttrValue::Str(CHANNEL_NAME.into()))),
        }
    }
}

/// A small spec with every kind of variable, for the tests of the schema and of the
/// in-memory file: two channels of three bins, four profiles, u16 counts with
/// components, a per-profile latitude and expected signal, one column of truth.
#[cfg(test)]
pub(super) fn example_spec() -> RawFileSpec {
    use super::spec::Variable;
    let var = |name: &str, dims, data: Vec<f64>| Variable {
        name: name.into(),
        dims,
        long_name: name.into(),
        units: "1".into(),
        attributes: vec![],
        data,
    };
    RawFileSpec {
        n_bins: 3,
        n_profiles: 4,
        first_profile: 0,
        channels: vec!["a".into(), "b".into()],
        count_width: CountWidth::U16,
        components: true,
        time_units: "seconds since 2000-01-01 00:00:00".into(),
        variables: vec![
            var("altitude", Dims::Bin, vec![1.0, 2.0, 3.0]),
            var("latitude", Dims::Profile, vec![]),
            var("expected_signal", Dims::ProfileChannelBin, vec![]),
            var("t2", Dims::ColumnChannelBin, vec![0.5; 6]),
        ],
        channel_text: vec![],
        n_columns: 1,
        streamed_columns: false,
        column_slots: 1,
        root_attributes: vec![("title".into(), AttrValue::Str("t".into()))],
        profile_coordinates: vec!["latitude".into()],
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::raw_file::check::RecordShape;

    #[test]
    fn every_variable_is_described_with_a_shape_that_holds_its_values() {
        let spec = example_spec();
        let vars = schema(&spec);
        let names: Vec<&str> = vars.iter().map(|v| v.name).collect();
        assert_eq!(
            names,
            [
                "profile",
                "channel",
                "bin",
                "channel_name",
                "column",
                "k",
                "profile_column",
                "profile_column_weight",
                "counts",
                "signal_counts",
                "background_counts",
                "dark_counts",
                "time",
                "n_shots",
                "pulse_energy",
                "altitude",
                "latitude",
                "expected_signal",
                "t2"
            ]
        );
        for v in &vars {
            assert_eq!(v.dims.len(), v.shape.len(), "{}", v.name);
            match v.values {
                Values::F64(d) => assert_eq!(d.len(), v.len(), "{}", v.name),
                Values::Text(t) => assert_eq!(t.len(), v.len(), "{}", v.name),
                _ => {}
            }
        }
        // the rows a record splits into are the schema's Row variables, in order
        let rows: Vec<&str> = vars
            .iter()
            .filter(|v| v.values == Values::PerProfile(PerProfile::Row))
            .map(|v| v.name)
            .collect();
        assert_eq!(rows.len(), 5);
        assert_eq!(RecordShape::of(&spec).per_profile.len(), 2);
        let coords = |name: &str| {
            vars.iter()
                .find(|v| v.name == name)
                .unwrap()
                .attributes
                .iter()
                .find(|(k, _)| k == "coordinates")
                .map(|(_, v)| v.clone())
        };
        let s = |t: &str| Some(AttrValue::Str(t.into()));
        assert_eq!(
            coords("counts"),
            s("time altitude range latitude channel_name")
        );
        assert_eq!(coords("n_shots"), s("time latitude"));
        assert_eq!(coords("t2"), s("altitude range channel_name"));
        assert_eq!(coords("pulse_energy"), s("time latitude channel_name"));
        assert_eq!(coords("channel_name"), None);
        assert_eq!(coords("channel"), None);
        assert_eq!(coords("latitude"), None);
        assert_eq!(coords("altitude"), None);
    }
}
