//! The `[refinement]` rows of the scene reference (`eddy scene-keys`), listed by hand while
//! the methods move to a registry, which will print them itself. Ranges and defaults are
//! those of [`super::Refinement::validate`] and the serde defaults in `params.rs`.

use crate::scene::reference::KeyRow;

/// One key of a method: method, key, type, default, allowed, meaning.
type Key = (
    &'static str,
    &'static str,
    &'static str,
    &'static str,
    &'static str,
    &'static str,
);

const KEYS: &[Key] = &[
    (
        "rankine",
        "beta",
        "number",
        "1",
        "[0, 1]",
        "Core-radius factor beta: r_c = beta sqrt(4 alpha_Oseen nu dt) (Wang et al. 2020 Eq. 11).",
    ),
    (
        "vrsph",
        "alpha",
        "number",
        "1",
        "[0, 2]",
        "Gain of the velocity refinement (Liu et al. 2021 Eq. 17); 1 is the ideal refinement.",
    ),
    (
        "mcvsph",
        "sample_fraction",
        "number",
        "0.01",
        "(0, 1]",
        "Fraction N / N_f of fluid particles paired with vortex particles.",
    ),
    (
        "mcvsph",
        "volume_coefficient",
        "number",
        "0.05",
        "[0, 1)",
        "Volume coefficient c of the vortex particles (Ye et al. Eq. 24).",
    ),
    (
        "mcvsph",
        "theta",
        "number",
        "0.5",
        "[0, 1)",
        "Opening parameter of the Biot–Savart treecode; 0 sums every pair directly.",
    ),
    (
        "micropolar",
        "nu_t",
        "number",
        "0.05",
        "[0, 1]",
        "Transfer coefficient nu_t, m^2/s.",
    ),
    (
        "micropolar",
        "micro_inertia",
        "number",
        "0.01",
        "> 0",
        "Micro-inertia per unit mass epsilon, m^2.",
    ),
    (
        "confinement",
        "epsilon",
        "number",
        "0.1",
        ">= 0",
        "Confinement strength epsilon, m/s.",
    ),
];

const METHODS: &str =
    "\"none\" | \"rankine\" | \"vrsph\" | \"mcvsph\" | \"micropolar\" | \"confinement\"";

/// The `[refinement]` keys: `method`, then each method's own, then `walls`.
pub fn rows() -> Vec<KeyRow> {
    let row = |key: &str, kind: &str, default: &str, allowed: &str, meaning: String| KeyRow {
        key: format!("refinement.{key}"),
        kind: kind.to_owned(),
        default: default.to_owned(),
        allowed: allowed.to_owned(),
        meaning,
        details: String::new(),
    };
    let mut rows = vec![row(
        "method",
        "string",
        "\"none\"",
        METHODS,
        "The SPH turbulence refinement; each method takes only its own keys.".to_owned(),
    )];
    rows.extend(
        KEYS.iter()
            .map(|(method, key, kind, default, allowed, meaning)| {
                row(
                    key,
                    kind,
                    default,
                    allowed,
                    format!("`method = \"{method}\"`: {meaning}"),
                )
            }),
    );
    rows.push(row(
        "walls",
        "bool",
        "false",
        "",
        "Every method but `none`: the wall samples take part in the difference operators \
         (models no-slip walls; pair it with `viscosity.boundary > 0`)."
            .to_owned(),
    ));
    rows
}
