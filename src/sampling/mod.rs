//! Photon-count samplers (issue 3).
