//! The checks a profile record passes before the writer buffers any of it (one place,
//! for one record at a time and for a batch checked in parallel).

use super::spec::{COMPONENT_NAMES, CountWidth, Dims, ProfileRecord, RawFileSpec};

/// The shape of the records a file takes: what a record is checked against.
#[derive(Clone, Debug)]
pub struct RecordShape {
    /// Profiles in the file.
    pub n_profiles: usize,
    /// Counts per profile: channels × bins.
    pub n_per_profile: usize,
    /// Channels: the pulse energies of a profile.
    pub n_channels: usize,
    /// The counts' integer width.
    pub count_width: CountWidth,
    /// Whether records carry signal, background and dark counts.
    pub components: bool,
    /// Dimensions and values per profile of each per-profile variable, in the spec's order.
    pub per_profile: Vec<(Dims, usize)>,
    /// Distinct columns of the scene (0: none).
    pub n_columns: usize,
    /// Column slots per profile (0: records carry none).
    pub column_slots: usize,
}

/// One profile's row of one (profile, channel, bin) variable.
#[derive(Clone, Copy, Debug)]
pub enum Row<'a> {
    /// Counts (the file's width was checked).
    Counts(&'a [u64]),
    /// A f64 variable (finite, checked).
    Floats(&'a [f64]),
}

impl RecordShape {
    /// The shape of `spec`'s records.
    pub fn of(spec: &RawFileSpec) -> RecordShape {
        RecordShape {
            n_profiles: spec.n_profiles,
            n_per_profile: spec.counts_per_profile(),
            n_channels: spec.channels.len(),
            count_width: spec.count_width,
            components: spec.components,
            per_profile: spec
                .variables
                .iter()
                .filter(|v| v.dims.per_profile())
                .map(|v| match v.dims {
                    Dims::Profile => (v.dims, 1),
                    Dims::ProfileChannel => (v.dims, spec.channels.len()),
                    _ => (v.dims, spec.counts_per_profile()),
                })
                .collect(),
            n_columns: spec.n_columns,
            column_slots: spec.column_slots,
        }
    }

    /// A checked record's rows of the (profile, channel, bin) variables in the file's
    /// order (`counts`, the components, the spec's variables), and its values of the
    /// (profile) and (profile, channel) variables in the spec's order.
    pub fn split<'a>(&self, rec: &ProfileRecord<'a>) -> (Vec<Row<'a>>, Vec<&'a [f64]>) {
        let mut rows = vec![Row::Counts(rec.counts)];
        if let Some(parts) = rec.components {
            rows.extend(parts.map(Row::Counts));
        }
        let mut columns = Vec::new();
        for (v, (dims, _)) in rec.values.iter().zip(&self.per_profile) {
            match dims {
                Dims::Profile | Dims::ProfileChannel => columns.push(*v),
                _ => rows.push(Row::Floats(v)),
            }
        }
        (rows, columns)
    }

    /// The record's columns: as many as the file's slots, and possible
    /// ([`super::integrity::check_profile_columns`], the rule every reader applies).
    fn check_columns(&self, rec: &ProfileRecord) -> Result<(), String> {
        let i = rec.index;
        let k = self.column_slots;
        if rec.columns.len() != k || rec.column_weights.len() != k {
            return Err(format!(
                "profile {i}: {} columns and {} weights given, the file has {k} slots",
                rec.columns.len(),
                rec.column_weights.len()
            ));
        }
        if k == 0 {
            return Ok(());
        }
        super::integrity::check_profile_columns(rec.columns, rec.column_weights, self.n_columns)
            .map_err(|why| {
                format!(
                    "profile {i}: columns {:?} of weights {:?} (the file has {} columns): {why}",
                    rec.columns, rec.column_weights, self.n_columns
                )
            })
    }

    /// Every check of a record but whether its profile was written before: its index is
    /// in range, its slices have the file's lengths, its numbers are finite, its counts
    /// fit the file's width and its components sum to its counts.
    pub fn check(&self, rec: &ProfileRecord) -> Result<(), String> {
        self.check_but_widths(rec)?;
        let parts = rec.components.iter().flatten().copied();
        let names = COMPONENT_NAMES.iter().copied();
        std::iter::once(("counts", rec.counts))
            .chain(names.zip(parts))
            .try_for_each(|(what, data)| self.check_width(rec.index, what, data))
    }

    /// Whether every count of `data` fits the file's width; the error names the first
    /// that does not (profile `i`, variable `what`).
    pub fn check_width(&self, i: usize, what: &str, data: &[u64]) -> Result<(), String> {
        let max = self.count_width.max_value();
        // `max` is 2^k − 1, so every count fits when their bitwise OR does: one
        // vectorized pass; the position is searched only on failure
        if data.iter().fold(0, |acc, &c| acc | c) <= max {
            return Ok(());
        }
        self.width_error(i, what, data)
    }

    /// The error of a `data` with a count beyond the file's width (none: `Ok`).
    pub fn width_error(&self, i: usize, what: &str, data: &[u64]) -> Result<(), String> {
        let max = self.count_width.max_value();
        match data.iter().position(|&c| c > max) {
            None => Ok(()),
            Some(b) => Err(format!(
                "profile {i}, value {b}: {what} {} exceeds the file's {} range (max {max})",
                data[b],
                self.count_width.name()
            )),
        }
    }

    /// [`RecordShape::check`] but whether the counts fit the file's width (for a caller
    /// that checks them as it narrows them: `memory`).
    pub fn check_but_widths(&self, rec: &ProfileRecord) -> Result<(), String> {
        let i = rec.index;
        if i >= self.n_profiles {
            return Err(format!(
                "profile index {i} out of range (the file holds {} profiles)",
                self.n_profiles
            ));
        }
        if rec.pulse_energy_j.len() != self.n_channels {
            return Err(format!(
                "profile {i}: {} pulse energies given, the file has {} channels",
                rec.pulse_energy_j.len(),
                self.n_channels
            ));
        }
        if let Some(e) = rec
            .pulse_energy_j
            .iter()
            .find(|e| !(e.is_finite() && **e >= 0.0))
        {
            return Err(format!(
                "profile {i}: pulse energy {e} J is not a finite non-negative number"
            ));
        }
        if rec.values.len() != self.per_profile.len() {
            return Err(format!(
                "profile {i}: {} per-profile variables given, the file has {}",
                rec.values.len(),
                self.per_profile.len()
            ));
        }
        for (k, (v, &(_, want))) in rec.values.iter().zip(&self.per_profile).enumerate() {
            if v.len() != want || !v.iter().fold(true, |ok, x| ok & x.is_finite()) {
                return Err(format!(
                    "profile {i}: per-profile variable {k} has {} values (want {want}) or a non-finite one",
                    v.len()
                ));
            }
        }
        if !rec.time_s.is_finite() {
            return Err(format!("profile {i}: time {} s is not finite", rec.time_s));
        }
        self.check_columns(rec)?;
        let n = self.n_per_profile;
        let check = |what: &str, data: &[u64]| {
            if data.len() != n {
                return Err(format!(
                    "profile {i}: {what} has {} values, the file has {n} per profile",
                    data.len()
                ));
            }
            Ok(())
        };
        check("counts", rec.counts)?;
        match (self.components, &rec.components) {
            (false, None) => Ok(()),
            (true, None) => Err(format!(
                "profile {i}: signal/background/dark counts missing"
            )),
            (false, Some(_)) => Err(format!(
                "profile {i}: component counts given but the file was created without them"
            )),
            (true, Some(parts)) => {
                for (name, part) in COMPONENT_NAMES.iter().zip(parts) {
                    check(name, part)?;
                }
                let [s, bg, d] = parts;
                match (0..n).find(|&b| {
                    s[b].checked_add(bg[b]).and_then(|x| x.checked_add(d[b])) != Some(rec.counts[b])
                }) {
                    None => Ok(()),
                    Some(b) => Err(format!(
                        "profile {i}, value {b}: signal + background + dark = {} + {} + {} does not equal counts {}",
                        s[b], bg[b], d[b], rec.counts[b]
                    )),
                }
            }
        }
    }
}
