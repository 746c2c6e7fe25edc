//! The truth a raw file carries beside the counts (format 3, docs/file-format.md "The
//! truth of each profile"): per distinct column of the scene, the optics by species at
//! each bin centre, the particle properties, `t2`, the particles' optics averaged over
//! each bin (`super::bin_mean`) and the molecular state; and the
//! channel's description (kind, polarization, filter, detector, molecular line).

use super::bin_mean::{BIN_MEAN_TRUTH, CELL_METHODS};
use super::spec::var;
use super::spec::{AttrValue, Dims, TextVariable, Variable};
use crate::detector::DeadTimeModel;
use crate::scenario::{ExpectedProfile, Lidar, Scenario};

/// A point truth of one bin of a column's channel.
pub(crate) type Truth = fn(&ExpectedProfile, usize) -> f64;

/// The point truth at the bin centre by species (model.md §8), each (column, channel,
/// bin): name, long name, units, value. The onboard product averages the same table over
/// each region bin's native bins (the onboard module's truth).
pub(crate) const COLUMN_TRUTH: [(&str, &str, &str, Truth); 21] = [
    (
        "alpha_mol",
        "molecular (Rayleigh) extinction coefficient at the bin centre",
        "m-1",
        |e, i| e.point[i].alpha_mol,
    ),
    (
        "alpha_aer",
        "aerosol extinction coefficient at the bin centre",
        "m-1",
        |e, i| e.point[i].alpha_aer,
    ),
    (
        "alpha_cld",
        "cloud extinction coefficient at the bin centre",
        "m-1",
        |e, i| e.point[i].alpha_cld,
    ),
    (
        "alpha_o3",
        "ozone absorption coefficient at the bin centre",
        "m-1",
        |e, i| e.point[i].alpha_o3,
    ),
    (
        "alpha_total",
        "total extinction coefficient at the bin centre: alpha_mol + alpha_o3 + alpha_aer + alpha_cld",
        "m-1",
        |e, i| e.point[i].alpha_total,
    ),
    (
        "beta_mol",
        "molecular backscatter coefficient at the bin centre, of the part of the line the channel sees",
        "m-1 sr-1",
        |e, i| e.point[i].beta_mol,
    ),
    (
        "beta_aer",
        "aerosol backscatter coefficient at the bin centre",
        "m-1 sr-1",
        |e, i| e.point[i].beta_aer,
    ),
    (
        "beta_cld",
        "cloud backscatter coefficient at the bin centre",
        "m-1 sr-1",
        |e, i| e.point[i].beta_cld,
    ),
    (
        "lidar_ratio_aer",
        "aerosol extinction-to-backscatter ratio alpha_aer/beta_aer (0 without aerosol)",
        "sr",
        |e, i| e.point[i].lidar_ratio_aer(),
    ),
    (
        "lidar_ratio_cld",
        "cloud extinction-to-backscatter ratio alpha_cld/beta_cld (0 without cloud)",
        "sr",
        |e, i| e.point[i].lidar_ratio_cld(),
    ),
    (
        "ms_factor_aer",
        "effective multiple-scattering factor of the aerosol extinction (1 without aerosol)",
        "1",
        |e, i| e.point[i].ms_factor_aer(),
    ),
    (
        "ms_factor_cld",
        "effective multiple-scattering factor of the cloud extinction (1 without cloud)",
        "1",
        |e, i| e.point[i].ms_factor_cld(),
    ),
    (
        "depol_aer",
        "aerosol particle linear depolarization ratio (0 without aerosol)",
        "1",
        |e, i| e.point[i].depol_aer(),
    ),
    (
        "depol_cld",
        "cloud particle linear depolarization ratio (0 without cloud)",
        "1",
        |e, i| e.point[i].depol_cld(),
    ),
    (
        "depol_mol",
        "molecular linear depolarization ratio of the part of the line the channel sees",
        "1",
        |e, i| e.point[i].depol_mol,
    ),
    (
        "depol_volume",
        "volume linear depolarization ratio (what an ideal parallel/perpendicular channel pair measures)",
        "1",
        |e, i| e.point[i].depol_volume(),
    ),
    (
        "t2",
        "two-way transmission to the bin centre: exp(-2 integral of (alpha_mol + alpha_o3 + ms_factor_aer alpha_aer + ms_factor_cld alpha_cld))",
        "1",
        |e, i| e.t2[i],
    ),
    (
        "single_scattering_attenuated_backscatter",
        "bin-averaged attenuated backscatter of single scattering alone (equal to attenuated_backscatter in the constant multiple-scattering model)",
        "m-1 sr-1",
        |e, i| e.attenuated_backscatter[i] / e.multiple_scattering_at(i).channel_ratio(),
    ),
    (
        "multiple_scattering_ratio",
        "apparent over single-scattering return of the bin, every polarization together (small-angle multiple scattering; 1 in the constant model); a polarization channel's own ratio also has its water-cloud depolarization factor: attenuated_backscatter / single_scattering_attenuated_backscatter",
        "1",
        |e, i| e.multiple_scattering_at(i).ratio,
    ),
    (
        "ms_factor_effective",
        "effective multiple-scattering factor eta of the particle optical depth to the bin centre: multiple_scattering_ratio = exp(2 (1 - eta) tau_particle); 1 without particles above and in the constant model",
        "1",
        |e, i| e.multiple_scattering_at(i).effective_factor(),
    ),
    (
        "ms_depolarization_water",
        "linear depolarization ratio of a water cloud's apparent return in the bin, from multiple scattering (Hu et al. 2006; small-angle model): what the channels see there instead of the droplets' own; 0 outside water cloud and in the constant model",
        "1",
        |e, i| e.multiple_scattering_at(i).water_depolarization,
    ),
];

/// The molecular state at the bin centre, each (column, bin): name, long name, units,
/// standard name, value.
const COLUMN_STATE: [(&str, &str, &str, &str, Truth); 4] = [
    (
        "pressure",
        "air pressure at the bin centre",
        "Pa",
        "air_pressure",
        |e, i| e.state[i].pressure_pa,
    ),
    (
        "temperature",
        "air temperature at the bin centre",
        "K",
        "air_temperature",
        |e, i| e.state[i].temperature_k,
    ),
    (
        "number_density",
        "air molecule number density at the bin centre (pressure / (k_B temperature), k_B = 1.380649e-23 J K-1)",
        "m-3",
        "",
        |e, i| e.state[i].number_density_m3,
    ),
    (
        "water_vapour_mixing_ratio",
        "mass mixing ratio of water vapour to dry air at the bin centre (written when the scene has a water-vapour profile)",
        "g kg-1",
        "humidity_mixing_ratio",
        |e, i| e.state[i].water_vapour_mixing_ratio * 1e3,
    ),
];

/// The truth of every column of the scene: `columns[c][k]` is column `c`'s model of
/// channel `k` (one column in a static scene). The species' optics and `t2` are
/// (column, channel, bin), the molecular state (column, bin); pressure and temperature
/// are NaN (their `_FillValue`) where the molecular source gives none.
pub fn column_variables(
    lidar: &Lidar,
    columns: &[&[ExpectedProfile]],
    species: &[usize],
) -> Vec<Variable> {
    let mut vars = Vec::new();
    let bin_means = BIN_MEAN_TRUTH.iter().map(|t| (t, &[CELL_METHODS][..]));
    for ((name, long_name, units, f), attrs) in
        COLUMN_TRUTH.iter().map(|t| (t, &[][..])).chain(bin_means)
    {
        let mut data = Vec::new();
        for e in columns.iter().flat_map(|col| col.iter()) {
            data.extend((0..e.n_bins()).map(|i| f(e, i)));
        }
        let mut v = var(name, Dims::ColumnChannelBin, long_name, units, attrs, data);
        if *name == "beta_mol" {
            v.attributes = beta_mol_attributes(lidar);
        }
        vars.push(v);
    }
    let config = &lidar.channels[0].loaded.config;
    let humid = crate::atmosphere::water_vapour::from_fields(config)
        || crate::atmosphere::water_vapour::profiles(config)
            .next()
            .is_some();
    if filter_tables(lidar) {
        let mut data = Vec::new();
        for e in columns.iter().flat_map(|col| col.iter()) {
            data.extend(e.point.iter().map(|o| o.molecular_transmission));
        }
        vars.push(var(
            "molecular_transmission",
            Dims::ColumnChannelBin,
            MOLECULAR_TRANSMISSION_LONG_NAME,
            "1",
            &[],
            data,
        ));
    }
    for (name, long_name, units, standard_name, f) in COLUMN_STATE {
        if name == "water_vapour_mixing_ratio" && !humid {
            continue;
        }
        let mut data = Vec::new();
        for e in columns.iter().map(|col| &col[0]) {
            data.extend((0..e.n_bins()).map(|i| f(e, i)));
        }
        let attrs: &[(&str, &str)] = match standard_name {
            "" => &[],
            s => &[("standard_name", s)],
        };
        let mut v = var(name, Dims::ColumnBin, long_name, units, attrs, data);
        if name != "number_density" {
            v.attributes
                .push(("_FillValue".into(), AttrValue::F64(f64::NAN)));
        }
        vars.push(v);
    }
    vars.extend(species_variables(columns, species));
    vars
}

/// The CAMS species (0-based, increasing) some of `columns` carries: the
/// `alpha_aer_<species>` variables a file of those columns writes. A changing scene's
/// file names its species before its columns are built (`SceneModel::aerosol_species`,
/// the same set from the scene's layers).
pub fn aerosol_species_of(columns: &[&[ExpectedProfile]]) -> Vec<usize> {
    let mut present: Vec<usize> = (columns.iter().flat_map(|col| col.iter()))
        .flat_map(|e| e.alpha_aer_by_species.iter().map(|s| s.0))
        .collect();
    present.sort_unstable();
    present.dedup();
    present
}

/// The aerosol extinction by CAMS species at the bin centre (a model-field scene with
/// aerosol, docs/file-format.md "Aerosol by species"): one (column, channel, bin)
/// variable `alpha_aer_<species>` (`alpha_aer_aermr04`, ...) per species of `species`
/// (the scene's, [`aerosol_species_of`]), in CAMS's order, 0 where a column has none of
/// it; they sum to `alpha_aer`.
fn species_variables(columns: &[&[ExpectedProfile]], species: &[usize]) -> Vec<Variable> {
    use crate::atmosphere::aerosol_species::CAMS_SPECIES;
    let mut vars = Vec::new();
    for &s in species {
        let species = &CAMS_SPECIES[s];
        let mut data = Vec::new();
        for e in columns.iter().flat_map(|col| col.iter()) {
            match e.alpha_aer_by_species.iter().find(|o| o.0 == s) {
                Some((_, v)) => data.extend_from_slice(v),
                None => data.extend(std::iter::repeat_n(0.0, e.n_bins())),
            }
        }
        let long_name = format!(
            "aerosol extinction coefficient at the bin centre of CAMS species {} ({}): its part of alpha_aer",
            species.short_name, species.description
        );
        let attrs = [("cams_species", species.short_name)];
        let name = format!("alpha_aer_{}", species.short_name);
        vars.push(var(
            &name,
            Dims::ColumnChannelBin,
            &long_name,
            "m-1",
            &attrs,
            data,
        ));
    }
    vars
}

/// Whether some channel's `f_m` follows the temperature (an HSRL filter table): then
/// `molecular_transmission` is written per (column, channel, bin), not per channel.
fn filter_tables(lidar: &Lidar) -> bool {
    lidar
        .channels
        .iter()
        .any(|c| c.loaded.channels[0].spectral_filter.is_some())
}

/// `beta_mol`'s attributes: the part of the line the channels see and its lidar ratio
/// (one value when every channel agrees; else see `molecular_line` and
/// `molecular_lidar_ratio`).
pub(crate) fn beta_mol_attributes(lidar: &Lidar) -> Vec<(String, AttrValue)> {
    let m = |k: usize| lidar.channels[k].atmosphere.molecular_lidar_ratio_sr();
    let same = |f: &dyn Fn(usize) -> String| (1..lidar.channels.len()).all(|k| f(k) == f(0));
    let line = |k: usize| lidar.channels[k].atmosphere.molecular_line_name();
    let ratio = |k: usize| m(k).to_string();
    let mut attrs = vec![(
        "line".to_string(),
        AttrValue::Str(if same(&line) {
            line(0)
        } else {
            "per channel: see molecular_line".into()
        }),
    )];
    if same(&ratio) {
        attrs.push(("lidar_ratio_sr".into(), AttrValue::F64(m(0))));
    }
    attrs
}

/// The string variables of the channel dimension (format 3): kind, species,
/// polarization, detection mode, acquisition mode, glue partner, dead-time model,
/// molecular line.
pub fn channel_text(lidar: &Lidar) -> Vec<TextVariable> {
    let text = |name: &str, long_name: &str, f: &dyn Fn(&Scenario) -> String| TextVariable {
        name: name.into(),
        long_name: long_name.into(),
        values: lidar.channels.iter().map(f).collect(),
    };
    vec![
        text(
            "channel_kind",
            "kind of scattering the channel sees: elastic, raman or hsrl_molecular",
            &|c| c.loaded.channels[0].kind.name().into(),
        ),
        text(
            "channel_species",
            "Raman-scattering species of a raman channel (empty otherwise)",
            &|c| {
                c.atmosphere
                    .raman
                    .as_ref()
                    .map_or_else(String::new, |r| r.species.name().into())
            },
        ),
        text(
            "polarization",
            "polarization the channel sees: total, parallel or perpendicular",
            &|c| c.loaded.config.instrument.channel.name().into(),
        ),
        text(
            "detection_mode",
            "the detector's mode: photon_counting, analog or both (a both detector is two channels, <name>_an and <name>_pc, recording the same photons)",
            &|c| {
                c.loaded.channels[0]
                    .detector()
                    .map(|d| d.mode)
                    .unwrap_or_default()
                    .name()
                    .into()
            },
        ),
        text(
            "acquisition_mode",
            "what this channel's counts are: photon_counting (photon counts) or analog (ADC codes summed over the shots)",
            &|c| c.loaded.channels[0].record.name().into(),
        ),
        text(
            "glue_partner",
            "the other channel of a both detector's pair, recording the same photons in the other mode (empty otherwise)",
            &|c| {
                c.loaded.channels[0]
                    .glue_partner
                    .map_or_else(String::new, |j| lidar.channels[j].channel_name.clone())
            },
        ),
        text(
            "dead_time_model",
            "detector dead-time model: none, nonparalyzable or paralyzable",
            &|c| match c.instrument.dead_time.map(|d| d.model) {
                None => "none".into(),
                Some(DeadTimeModel::Nonparalyzable) => "nonparalyzable".into(),
                Some(DeadTimeModel::Paralyzable) => "paralyzable".into(),
            },
        ),
        text(
            "molecular_line",
            "what the channel's beta_mol is: the part of the elastic molecular line it sees (cabannes; cabannes+partial_rr, the Cabannes line and the rotational Raman lines the filter passes; or whole), or a Raman band (raman_N2)",
            &|c| c.atmosphere.molecular_line_name(),
        ),
    ]
}

/// The numeric variables of the channel dimension added in format 3 and `overlap`.
pub fn instrument_variables(lidar: &Lidar, e0: &ExpectedProfile) -> Vec<Variable> {
    use Dims::{Bin, Channel};
    let per = |f: fn(&Scenario) -> f64| lidar.channels.iter().map(f).collect::<Vec<f64>>();
    let constant_f_m = (!filter_tables(lidar)).then(|| {
        var(
            "molecular_transmission",
            Channel,
            MOLECULAR_TRANSMISSION_LONG_NAME,
            "1",
            &[],
            per(|c| c.loaded.channels[0].lines.molecular),
        )
    });
    constant_f_m.into_iter().chain([
        var(
            "emission_wavelength",
            Channel,
            "wavelength of the laser line",
            "nm",
            &[],
            per(|c| c.instrument.wavelength_nm),
        ),
        var(
            "detection_wavelength",
            Channel,
            "wavelength of the detected line",
            "nm",
            &[],
            per(|c| c.loaded.channels[0].detection_wavelength_nm()),
        ),
        var(
            "crosstalk",
            Channel,
            "fraction of the other polarization's light the channel sees",
            "1",
            &[],
            per(|c| c.loaded.config.instrument.crosstalk),
        ),
        var(
            "relative_gain",
            Channel,
            "gain of the channel relative to its nominal lidar constant",
            "1",
            &[],
            per(|_| 1.0),
        ),
        var(
            "filter_width",
            Channel,
            "interference filter bandwidth (FWHM)",
            "nm",
            &[],
            per(|c| c.loaded.config.instrument.filter_width_nm),
        ),
        var(
            "particle_transmission",
            Channel,
            "share of the particle line the channel's filter passes, f_p (1 but in hsrl_molecular channels)",
            "1",
            &[],
            per(|c| c.loaded.channels[0].lines.particle),
        ),
        var(
            "diattenuation",
            Channel,
            "diattenuation D of the receiving optics: (1+D) of the light polarized parallel to the laser passes, (1-D) of the perpendicular",
            "1",
            &[],
            per(|c| c.loaded.config.instrument.diattenuation),
        ),
        var(
            "receiver_rotation",
            Channel,
            "rotation of the polarization plane in front of the polarizing beam splitter (0 to measure, +-45 in Delta-90 calibration runs)",
            "degree",
            &[],
            per(|c| c.loaded.config.instrument.receiver_rotation_deg),
        ),
        Variable {
            attributes: vec![("_FillValue".into(), AttrValue::F64(f64::NAN))],
            ..var(
                "polarization_calibration_constant",
                Channel,
                "Delta-90 calibration constant eta* = eta T_R/T_T of a perpendicular channel R relative to the parallel channel T at the same laser wavelength, else to the total channel there: eta the ratio of their lidar constants, T_R/T_T their analysers' mean transmissions (1 over a parallel, 1/2 over a total channel); what the Delta-90 method sqrt(ratio(+45) ratio(-45)) recovers; NaN for other channels",
                "1",
                &[],
                calibration_constants(lidar),
            )
        },
        var(
            "band_transmission",
            Channel,
            "share of the Raman band the channel's filter passes (1 but in raman channels that give less)",
            "1",
            &[],
            per(|c| c.loaded.channels[0].band_transmission),
        ),
        var(
            "molecular_lidar_ratio",
            Channel,
            "extinction-to-backscatter ratio of the part of the molecular line the channel sees: alpha_mol / beta_mol",
            "sr",
            &[],
            per(|c| c.atmosphere.molecular_lidar_ratio_sr()),
        ),
        var(
            "overlap",
            Bin,
            "overlap function eta(r) at the bin centre",
            "1",
            &[],
            e0.overlap.clone(),
        ),
    ])
    .collect()
}

/// Each channel's Δ90 calibration constant η* (docs/model.md §4c, Eq. 4c.1;
/// [`crate::receiver::delta90_calibration_constant`]): for a perpendicular channel,
/// relative to the elastic parallel channel at the same laser wavelength, else to the
/// elastic total channel there (the total + cross layout); NaN for other channels and
/// where there is no such reference channel.
fn calibration_constants(lidar: &Lidar) -> Vec<f64> {
    use crate::config::Channel as Pol;
    use crate::receiver::ChannelKind;
    let pol = |c: &Scenario| c.loaded.config.instrument.channel;
    let reference = |c: &Scenario, want: Pol| {
        lidar.channels.iter().find(|p| {
            pol(p) == want
                && p.loaded.channels[0].kind == ChannelKind::Elastic
                && p.instrument.wavelength_nm == c.instrument.wavelength_nm
        })
    };
    let optics = |c: &Scenario| (pol(c), c.loaded.config.instrument.crosstalk);
    lidar
        .channels
        .iter()
        .map(|c| {
            if pol(c) != Pol::Perpendicular {
                return f64::NAN;
            }
            match reference(c, Pol::Parallel).or_else(|| reference(c, Pol::Total)) {
                Some(p) => crate::receiver::delta90_calibration_constant(
                    c.instrument.signal_constant,
                    optics(c),
                    p.instrument.signal_constant,
                    optics(p),
                ),
                None => f64::NAN,
            }
        })
        .collect()
}

/// `molecular_transmission`'s long name, per channel or per (column, channel, bin).
const MOLECULAR_TRANSMISSION_LONG_NAME: &str = "share of the molecular (Cabannes) line the channel's filter passes, f_m (1 but in hsrl_molecular channels; per bin where a filter table makes it follow the temperature)";
