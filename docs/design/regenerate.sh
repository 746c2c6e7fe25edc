#!/bin/sh
# Reruns every command of docs/design-study.md, rewriting the CSVs and PNGs of
# docs/design/ (the onboard report docs/design/caliop_onboard.csv included: copy its
# numbers into the table of section 4), and the orbit curtain of docs/scenes.md
# (docs/caliop_orbit_curtain.png). Run from anywhere after `cargo build --release`;
# LIDARSIM=path overrides the binary. Deterministic: a rerun at the same commit gives
# the same files.
set -eu
cd "$(dirname "$0")/../.."
root=$(pwd)
L=${LIDARSIM:-$root/target/release/lidarsim}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT INT TERM

# 1. Energy and repetition rate: the cirrus at 11 km
"$L" sweep configs/paper/scenario1.toml \
  --vary instrument.pulse_energy_j=1e-4..1e-1:log:25 --vary instrument.rep_rate_hz=10..250:25 \
  --metric snr_at:11km --metric max_altitude:snr=3 \
  --csv docs/design/energy_rate.csv --png docs/design/energy_rate.png

# 2. How long to average: molecules at 10 km, night and day
"$L" sweep configs/paper/scenario6.toml \
  --vary instrument.pulse_energy_j=1e-4..1e-1:log:31 --metric time_to_snr:10@10km \
  --csv docs/design/time_night.csv --png docs/design/time_night.png
"$L" sweep configs/paper/scenario6.toml --set background.radiance=1.1e15 \
  --vary instrument.pulse_energy_j=1e-4..1e-1:log:31 --metric time_to_snr:10@10km \
  --csv docs/design/time_day.csv --png docs/design/time_day.png

# 3. Telescope area
"$L" sweep configs/paper/scenario1.toml --set instrument.pulse_energy_j=0.01 \
  --set instrument.rep_rate_hz=100 --vary instrument.telescope_area_m2=0.01..0.3:log:25 \
  --metric max_altitude:snr=3 --csv docs/design/telescope.csv --png docs/design/telescope.png

# 4. Onboard schemes (depends on the `caliop` scheme of src/onboard/scheme.rs)
"$L" onboard configs/instruments/caliop_3ch.toml --set acquisition.top_altitude_km=40 \
  --set acquisition.bottom_altitude_km=-2 --set acquisition.profiles=20 \
  --scheme caliop --scheme uniform:1 --scheme uniform:15 \
  -o "$tmp/design_product.h5" --report docs/design/caliop_onboard.csv

# 5. Pulses in flight: a refusal, no figure
if "$L" expect configs/paper/scenario1.toml --set instrument.rep_rate_hz=5000 \
  --set acquisition.top_altitude_km=40 >/dev/null 2>"$tmp/pulses.txt"; then
  echo "section 5: expected a refusal of 5000 Hz" >&2
  exit 1
fi
cat "$tmp/pulses.txt"

# 6. The CALIOP-like instrument through the same questions
"$L" sweep configs/instruments/caliop_532.toml \
  --vary instrument.pulse_energy_j=0.01..0.3:log:20 --vary instrument.telescope_area_m2=0.1..1.0:log:20 \
  --metric snr_at:20km --metric max_altitude:snr=3 \
  --csv docs/design/caliop_energy_area.csv --png docs/design/caliop_energy_area.png
"$L" sweep configs/instruments/caliop_532.toml \
  --vary instrument.pulse_energy_j=0.01..0.3:log:20 --metric time_to_snr:10@10km \
  --csv docs/design/caliop_time_night.csv --png docs/design/caliop_time_night.png
"$L" sweep configs/instruments/caliop_532.toml --set background.model=\"solar\" \
  --set background.solar_zenith_deg=30 --set 'surface={kind="land"}' \
  --vary instrument.pulse_energy_j=0.01..0.3:log:20 --metric time_to_snr:10@10km \
  --csv docs/design/caliop_time_day.csv --png docs/design/caliop_time_day.png

# docs/scenes.md: counts per shot along the orbit (run beside the file, so that the
# figure's title names caliop_orbit.h5)
(cd "$tmp" && "$L" simulate "$root/configs/instruments/caliop_orbit.toml" -o caliop_orbit.h5 &&
  "$L" curtain caliop_orbit.h5 --png "$root/docs/caliop_orbit_curtain.png")

# docs/figures.md: the quicklooks and the S/N map (run beside the files, so that the
# figures' titles name them)
mkdir -p docs/figures
"$L" snr-map configs/paper/scenario1.toml --png docs/figures/snr_map_scenario1.png
(cd "$tmp" && "$L" quicklook caliop_orbit.h5 --truth --png "$root/docs/figures/quicklook_orbit.png")
(cd "$tmp" && "$L" quicklook caliop_orbit.h5 --x-axis time --png "$root/docs/figures/quicklook_orbit_time.png" &&
  "$L" quicklook caliop_orbit.h5 --x-axis along-track --png "$root/docs/figures/quicklook_orbit_along_track.png")
(cd "$tmp" && "$L" simulate "$root/configs/instruments/caliop_3ch.toml" -o caliop_3ch.h5 --profiles 200 &&
  "$L" quicklook caliop_3ch.h5 --png "$root/docs/figures/quicklook_pair.png" &&
  "$L" quicklook caliop_3ch.h5 --channels 532_parallel,532_perpendicular,1064_total \
    --png "$root/docs/figures/quicklook_channels.png")
# the MPL-like hour (shot by shot: about 3 to 5 minutes on 2 cores)
(cd "$tmp" && "$L" simulate "$root/configs/ground/mpl_like.toml" -o mpl.h5 --profiles 60 \
  --set platform.latitude_deg=38.99 --set platform.longitude_deg=-76.84 &&
  "$L" quicklook mpl.h5 --png "$root/docs/figures/quicklook_altitude_range.png" --altitude-range 0,6 &&
  "$L" quicklook mpl.h5 --png "$root/docs/figures/quicklook_mask_snr.png" --mask-snr 3 &&
  "$L" quicklook mpl.h5 --png "$root/docs/figures/quicklook_profile.png" --x-axis profile --altitude-range 0,12)
(cd "$tmp" && "$L" onboard "$root/configs/instruments/caliop_3ch.toml" --set acquisition.top_altitude_km=40 \
  --set acquisition.bottom_altitude_km=-2 --set acquisition.profiles=200 --scheme caliop -o caliop_3ch_product.h5 &&
  "$L" quicklook caliop_3ch_product.h5 --truth --png "$root/docs/figures/quicklook_product.png")

echo "section 4 (onboard report):"
cat docs/design/caliop_onboard.csv
