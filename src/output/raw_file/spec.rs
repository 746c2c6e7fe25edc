//! The raw file's vocabulary, shared by its writer, its in-memory twin and its readers:
//! the format version, the dimension and reserved names, a variable's description, a
//! run's file spec, and the profile record a sink takes.

use crate::error::{Error, Result};

/// `lidarsim_format_version` of the files this code writes.
pub const FORMAT_VERSION: i32 = 5;
/// The CF version the files declare (CF-1.9 and later allow the unsigned counts).
pub const CONVENTIONS: &str = "CF-1.10";
/// Name of the profile dimension (and of its coordinate variable).
pub const PROFILE_DIM: &str = "profile";
/// Name of the channel dimension (and of its coordinate variable: the channel numbers
/// 0, 1, … from format 5, the names before).
pub const CHANNEL_DIM: &str = "channel";
/// Name of the channels' names (format 5): a string auxiliary coordinate (channel),
/// listed in the `coordinates` attribute of every variable with the channel dimension.
pub const CHANNEL_NAME: &str = "channel_name";
/// Name of the range-bin dimension (and of its coordinate variable).
pub const BIN_DIM: &str = "bin";
/// Name of the dimension of the scene's distinct columns (and of its coordinate).
pub const COLUMN_DIM: &str = "column";
/// Name of the dimension of a profile's column slots.
pub const SLOT_DIM: &str = "k";
/// Names of the (profile, k) variables: which columns a profile's shots saw, and the
/// share of its shots that saw each.
pub const PROFILE_COLUMN_NAMES: [&str; 2] = ["profile_column", "profile_column_weight"];
/// Names of the per-component count variables, in the order of
/// [`ProfileRecord::components`]: signal, background, dark.
pub const COMPONENT_NAMES: [&str; 3] = ["signal_counts", "background_counts", "dark_counts"];
/// Variable names the layout itself defines; a [`Variable`] may not use them.
pub const RESERVED_NAMES: [&str; 15] = [
    PROFILE_DIM,
    CHANNEL_DIM,
    CHANNEL_NAME,
    BIN_DIM,
    COLUMN_DIM,
    SLOT_DIM,
    PROFILE_COLUMN_NAMES[0],
    PROFILE_COLUMN_NAMES[1],
    "counts",
    "time",
    "n_shots",
    "pulse_energy",
    COMPONENT_NAMES[0],
    COMPONENT_NAMES[1],
    COMPONENT_NAMES[2],
];

/// Integer width of the stored counts, chosen from the largest count expected (see
/// [`CountWidth::for_max_count`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum CountWidth {
    /// Unsigned 16-bit: counts up to 65 535.
    U16,
    /// Unsigned 32-bit: counts up to 4 294 967 295.
    U32,
    /// Unsigned 64-bit.
    U64,
}

impl CountWidth {
    /// The largest count this width stores.
    pub fn max_value(self) -> u64 {
        match self {
            CountWidth::U16 => u64::from(u16::MAX),
            CountWidth::U32 => u64::from(u32::MAX),
            CountWidth::U64 => u64::MAX,
        }
    }

    /// Bytes per stored count.
    pub fn bytes(self) -> usize {
        match self {
            CountWidth::U16 => 2,
            CountWidth::U32 => 4,
            CountWidth::U64 => 8,
        }
    }

    /// Lower-case type name, e.g. `"u16"`, for messages.
    pub fn name(self) -> &'static str {
        match self {
            CountWidth::U16 => "u16",
            CountWidth::U32 => "u32",
            CountWidth::U64 => "u64",
        }
    }

    /// The narrowest width that holds a Poisson count of mean `max_expected` (the largest
    /// expected count of any bin in any profile) with safe headroom:
    /// `mean + 20·sqrt(mean) + 64`. A Poisson draw exceeds that bound with probability
    /// below 1e-80, so a width chosen here never overflows in practice (and
    /// `RawFileWriter::write_profile` refuses, rather than wraps, if it does).
    ///
    /// Errors if `max_expected` is negative or not finite, or if even u64 cannot hold it.
    pub fn for_max_count(max_expected: f64) -> Result<CountWidth> {
        if !max_expected.is_finite() || max_expected < 0.0 {
            return Err(Error::Unsupported(format!(
                "cannot size the raw file's counts: the largest expected count per bin is \
                 {max_expected:e}, not a finite non-negative number"
            )));
        }
        let bound = max_expected + 20.0 * max_expected.sqrt() + 64.0;
        for width in [CountWidth::U16, CountWidth::U32, CountWidth::U64] {
            // `as f64` rounds u64::MAX up to 2^64, so compare strictly below it.
            if bound < width.max_value() as f64 {
                return Ok(width);
            }
        }
        Err(Error::Unsupported(format!(
            "the largest expected count per bin ({max_expected:e}) does not fit a 64-bit \
             counter; accumulate fewer shots per profile"
        )))
    }
}

/// The dimensions of a [`Variable`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Dims {
    /// (bin): e.g. `altitude`, `range`, `range_weight`, the point truth.
    Bin,
    /// (channel): e.g. `lidar_constant`.
    Channel,
    /// (channel, bin), channel-major: e.g. `expected_signal`, `attenuated_backscatter`.
    ChannelBin,
    /// (profile): written with each profile ([`ProfileRecord::values`]), e.g. `latitude`.
    Profile,
    /// (profile, channel, bin): written with each profile, e.g. the expectations of a
    /// scene that changes along the track.
    ProfileChannelBin,
    /// (profile, channel): written with each profile, one value per channel, e.g. a
    /// changing scene's sky background per bin.
    ProfileChannel,
    /// (column, bin), column-major: e.g. the molecular state of each column.
    ColumnBin,
    /// (column, channel, bin), column-major then channel-major: the truth of each
    /// distinct column of the scene.
    ColumnChannelBin,
}

impl Dims {
    /// Whether the variable has a profile dimension (its values come with each profile).
    pub fn per_profile(self) -> bool {
        matches!(
            self,
            Dims::Profile | Dims::ProfileChannel | Dims::ProfileChannelBin
        )
    }
}

/// A f64 variable written at creation beside the counts.
#[derive(Clone, Debug, PartialEq)]
pub struct Variable {
    /// Name in the file (not one of [`RESERVED_NAMES`]).
    pub name: String,
    /// Its dimensions.
    pub dims: Dims,
    /// CF `long_name`.
    pub long_name: String,
    /// CF `units` (UDUNITS string, `"1"` for dimensionless).
    pub units: String,
    /// Further attributes (`standard_name`, `positive`, `comment`, a `_FillValue`, ...).
    pub attributes: Vec<(String, AttrValue)>,
    /// The values, channel-major for (channel, bin); empty for a per-profile variable,
    /// whose rows come with each profile.
    pub data: Vec<f64>,
}

/// A string variable of the channel dimension, written at creation (e.g. `polarization`).
#[derive(Clone, Debug, PartialEq)]
pub struct TextVariable {
    /// Name in the file (not one of [`RESERVED_NAMES`]).
    pub name: String,
    /// CF `long_name`.
    pub long_name: String,
    /// One value per channel.
    pub values: Vec<String>,
}

/// The value of a root (global) attribute.
#[derive(Clone, Debug, PartialEq)]
pub enum AttrValue {
    /// Text (a variable-length UTF-8 string, netCDF `NC_STRING`).
    Str(String),
    /// An unsigned integer (netCDF `NC_UINT64`), e.g. the seed.
    U64(u64),
    /// A signed integer (netCDF `NC_INT`), e.g. the format version.
    I32(i32),
    /// A floating-point number (netCDF `NC_DOUBLE`).
    F64(f64),
}

/// Everything about a raw file that is known before the first profile.
#[derive(Clone, Debug)]
pub struct RawFileSpec {
    /// Range bins per profile (length of the `bin` dimension), at least 1.
    pub n_bins: usize,
    /// Profiles in the file, at least 1; every one must be written before
    /// `RawFileWriter::finish`.
    pub n_profiles: usize,
    /// Index in the run of the file's first profile: the `profile` coordinate holds
    /// `first_profile .. first_profile + n_profiles` (0 but in a shard file,
    /// docs/architecture.md's shards); [`ProfileRecord::index`] stays the row in the file.
    pub first_profile: usize,
    /// Channel names (the `channel_name` coordinate; `channel` numbers them from 0), at
    /// least one.
    pub channels: Vec<String>,
    /// Integer width of `counts` (and of the component variables).
    pub count_width: CountWidth,
    /// Whether the file also holds `signal_counts`, `background_counts` and
    /// `dark_counts`; each [`ProfileRecord`] must then carry them.
    pub components: bool,
    /// CF units of `time`, e.g. `seconds since 2000-01-01 00:00:00`.
    pub time_units: String,
    /// Variables written at creation, in this order.
    pub variables: Vec<Variable>,
    /// String variables of the channel dimension, written at creation after `channel`.
    pub channel_text: Vec<TextVariable>,
    /// Distinct columns of the scene (the `column` dimension of the truth variables;
    /// 0: no such dimension).
    pub n_columns: usize,
    /// Whether the (column, …) variables carry no values here: a scene whose columns are
    /// built as its profiles need them hands each column's rows to
    /// [`ProfileSink::write_column`] (memory flat in the track's length).
    pub streamed_columns: bool,
    /// Column slots per profile (the `k` dimension of `profile_column` and
    /// `profile_column_weight`; 0: no such variables); each [`ProfileRecord`] then
    /// carries this many of each.
    pub column_slots: usize,
    /// Root attributes, in this order.
    pub root_attributes: Vec<(String, AttrValue)>,
    /// Further coordinates of the profile dimension (e.g. `latitude longitude`), listed in
    /// the `coordinates` attribute of every (profile, …) variable.
    pub profile_coordinates: Vec<String>,
}

impl RawFileSpec {
    /// Counts per profile: channels × bins.
    pub fn counts_per_profile(&self) -> usize {
        self.channels.len() * self.n_bins
    }
}

/// Where a run's profiles go: the file (`RawFileWriter`) or memory
/// (`MemoryWriter`); each checks a record before it keeps any of it.
pub trait ProfileSink: Send {
    /// Takes one profile (in any order, each once).
    fn write_profile(&mut self, rec: &ProfileRecord) -> Result<()>;

    /// Takes column `column`'s truth (with [`RawFileSpec::streamed_columns`]): one row per
    /// (column, …) variable in the spec's order, each of its values per column.
    fn write_column(&mut self, column: usize, rows: &[&[f64]]) -> Result<()>;
}

/// One profile, as handed to `RawFileWriter::write_profile`.
#[derive(Clone, Copy, Debug)]
pub struct ProfileRecord<'a> {
    /// Row in the file, `0..n_profiles`; profiles may come in any order, each once.
    pub index: usize,
    /// Profile centre time since `acquisition.start_time`, s.
    pub time_s: f64,
    /// Shots accumulated in this profile.
    pub n_shots: u64,
    /// Mean emitted pulse energy of the profile's shots at each channel's laser line, J
    /// (the energy monitor's reading), one per channel: `E0_c·Σf_s/M` with `E0_c` the
    /// channel's nominal energy (`nominal_pulse_energy`).
    pub pulse_energy_j: &'a [f64],
    /// Accumulated raw counts, channel-major: `counts[c·n_bins + b]`.
    pub counts: &'a [u64],
    /// Signal, background and dark counts laid out as `counts`; present exactly when the
    /// spec asked for components, and then summing to `counts`.
    pub components: Option<[&'a [u64]; 3]>,
    /// This profile's row of every per-profile variable of the spec, in the spec's order
    /// (one value for (profile), one per channel for (profile, channel), channels × bins
    /// channel-major for (profile, channel, bin)).
    pub values: &'a [&'a [f64]],
    /// The columns this profile's shots saw (indices of the `column` dimension, each
    /// once, −1 for an unused slot), [`RawFileSpec::column_slots`] of them.
    pub columns: &'a [i32],
    /// The share of the profile's shots that saw each of `columns` (0 for an unused
    /// slot), summing to 1.
    pub column_weights: &'a [f64],
}

/// A float variable with its CF `long_name`, `units` and further text attributes.
pub(super) fn var(
    name: &str,
    dims: Dims,
    long_name: &str,
    units: &str,
    attributes: &[(&str, &str)],
    data: Vec<f64>,
) -> Variable {
    Variable {
        name: name.into(),
        dims,
        long_name: long_name.into(),
        units: units.into(),
        attributes: attributes
            .iter()
            .map(|(k, v)| (k.to_string(), AttrValue::Str(v.to_string())))
            .collect(),
        data,
    }
}
