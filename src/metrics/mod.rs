//! Per-step diagnostics and probes.
