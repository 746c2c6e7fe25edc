//! Signal-to-noise ratio of accumulated photon counts (model.md §2, paper Eq. 4).

/// Eq. 4: `S/N = M·λ_sig / sqrt(M·(λ_sig + λ_bkg + λ_dc))` for `M` accumulated shots and
/// per-shot expectations λ; the same as `N_sig/sqrt(N_sig+N_bkg+N_dc)·sqrt(Δt·fL·TC)`.
/// The background is taken as known exactly. Zero when nothing is detected.
pub fn eq4(signal: f64, background: f64, dark: f64, shots: f64) -> f64 {
    let total = shots * (signal + background + dark);
    if total > 0.0 {
        shots * signal / total.sqrt()
    } else {
        0.0
    }
}

/// S/N when the retrieval subtracts a background estimated from `background_bins`
/// signal-free bins: their mean adds `M·(λ_bkg+λ_dc)/n_b` to the variance (model.md §2).
pub fn with_estimated_background(
    signal: f64,
    background: f64,
    dark: f64,
    shots: f64,
    background_bins: usize,
) -> f64 {
    let variance =
        shots * (signal + background + dark) + shots * (background + dark) / background_bins as f64;
    if variance > 0.0 {
        shots * signal / variance.sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn eq4_forms_agree() {
        // rates N = λ/Δt with Δt = 2 µs, fL = 10 Hz, TC = 100 s
        let (dt, fl, tc): (f64, f64, f64) = (2e-6, 10.0, 100.0);
        let (s, b, d): (f64, f64, f64) = (0.3, 0.05, 4e-4);
        let rate_form = (s / dt) / ((s + b + d) / dt).sqrt() * (dt * fl * tc).sqrt();
        assert!((eq4(s, b, d, fl * tc) - rate_form).abs() < 1e-9 * rate_form);
    }

    #[test]
    fn estimated_background_costs_snr() {
        let known = eq4(0.01, 0.1, 0.0, 1000.0);
        let est = with_estimated_background(0.01, 0.1, 0.0, 1000.0, 10);
        assert!(est < known);
        assert!(
            (with_estimated_background(0.01, 0.1, 0.0, 1000.0, usize::MAX) - known).abs() < 1e-12
        );
        assert_eq!(eq4(0.0, 0.0, 0.0, 10.0), 0.0);
    }
}
