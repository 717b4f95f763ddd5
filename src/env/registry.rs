//! Every environment ID: the list of families, one line each, and the lookup.

use super::family::{Family, Spec};
use super::spec::EnvSpec;
use super::{calibrate, cavity, channel, cube, cylinder, kolmogorov, naca, pinball, pipe, sphere, square, wing_tbl, EnvInputError};

/// The families, in listing order. A new family is one file implementing [`Family`] and one
/// line here.
pub const FAMILIES: &[&dyn Family] = &[
    &cylinder::Cylinder,
    &pinball::Pinball,
    &square::Square,
    &cavity::Cavity,
    &naca::Naca,
    &pipe::Pipe,
    &sphere::Sphere,
    &cube::Cube,
    &kolmogorov::KolmogorovFlows,
    &channel::Channels,
    &wing_tbl::WingTbls,
];

/// All registered specs, in a fixed order, with their committed statistics.
pub fn all() -> Vec<Spec> {
    FAMILIES.iter().flat_map(|f| f.specs()).collect()
}

/// The spec of `id`, or an error naming the closest IDs.
pub fn lookup(id: &str) -> Result<Spec, EnvInputError> {
    let specs = all();
    if let Some(s) = specs.iter().find(|s| s.id() == id) {
        return Ok(s.clone());
    }
    let mut ids: Vec<(usize, String)> = specs
        .iter()
        .map(|s| (edit_distance(&s.id().to_lowercase(), &id.to_lowercase()), s.id().to_string()))
        .collect();
    ids.sort();
    Err(EnvInputError::UnknownEnv {
        id: id.to_string(),
        closest: ids.into_iter().map(|(_, id)| id).collect(),
    })
}

/// A lattice-Boltzmann environment's flow, 2D ([`EnvSpec`]) or 3D
/// ([`Env3Spec`](super::spec3::Env3Spec)), as validation sees it.
pub trait LbmFlowSpec {
    fn id(&self) -> &str;
    /// The uncontrolled flow the environment runs.
    fn flow_setup(&self) -> crate::flow::FlowSetup;
    /// The bundled validation case whose references judge this flow, if there is one.
    fn validation_case(&self) -> Option<String>;
}

impl LbmFlowSpec for EnvSpec {
    fn id(&self) -> &str {
        &self.id
    }
    fn flow_setup(&self) -> crate::flow::FlowSetup {
        EnvSpec::flow_setup(self)
    }
    fn validation_case(&self) -> Option<String> {
        EnvSpec::validation_case(self)
    }
}

impl LbmFlowSpec for super::spec3::Env3Spec {
    fn id(&self) -> &str {
        &self.id
    }
    fn flow_setup(&self) -> crate::flow::FlowSetup {
        super::spec3::Env3Spec::flow_setup(self)
    }
    fn validation_case(&self) -> Option<String> {
        super::spec3::Env3Spec::validation_case(self)
    }
}

/// The lattice-Boltzmann flow of a registered spec, 2D or 3D; `None` for the spectral ones.
pub fn lbm_flow(spec: &Spec) -> Option<&dyn LbmFlowSpec> {
    if let Some(s) = spec.downcast::<EnvSpec>() {
        return Some(s);
    }
    spec.downcast::<super::spec3::Env3Spec>().map(|s| s as &dyn LbmFlowSpec)
}

/// The lattice-Boltzmann specs among all (those the flow layer builds).
pub fn lbm_specs() -> Vec<EnvSpec> {
    all().iter().filter_map(|s| s.downcast::<EnvSpec>().cloned()).collect()
}

/// The lattice-Boltzmann spec of `id` (an error for an unknown ID or another solver's).
pub fn lbm_spec(id: &str) -> Result<EnvSpec, EnvInputError> {
    let spec = lookup(id)?;
    spec.downcast::<EnvSpec>().cloned().ok_or_else(|| EnvInputError::NotLbm {
        id: id.to_string(),
        solver: spec.solver(),
    })
}

/// Lattice-Boltzmann specs as registry entries, with the committed observation statistics
/// attached (a family's `specs`).
pub(super) fn lbm(specs: impl IntoIterator<Item = EnvSpec>) -> Vec<Spec> {
    specs
        .into_iter()
        .map(|mut s| {
            calibrate::attach(&mut s, calibrate::table());
            Spec::new(s)
        })
        .collect()
}

/// 3D lattice-Boltzmann specs as registry entries, with the committed observation statistics of
/// the default level attached.
pub(super) fn lbm3(specs: impl IntoIterator<Item = super::spec3::Env3Spec>) -> Vec<Spec> {
    specs
        .into_iter()
        .map(|mut s| {
            if let Some(n) = super::lbm_env3::committed_normalization(&s, crate::flow::Level::Default) {
                s.normalization = n;
            }
            Spec::new(s)
        })
        .collect()
}

/// Levenshtein distance (for "did you mean").
pub(crate) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            cur[j + 1] = (prev[j] + usize::from(ca != *cb)).min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_are_unique_and_found() {
        let specs = all();
        let mut ids: Vec<&str> = specs.iter().map(|s| s.id()).collect();
        ids.sort();
        ids.dedup();
        assert_eq!(ids.len(), specs.len());
        for id in &ids {
            assert!(crate::data::read::is_env_id(id), "{id} has the syntax files are checked against");
        }
        for bad in ["../x", "/abs", "", "1abc", "a/b", "a.b", "a-b", &"A".repeat(65)] {
            assert!(!crate::data::read::is_env_id(bad), "{bad}");
        }
        assert!(lookup("Cylinder_2D_Re100").is_ok());
        assert!(lookup("Kolmogorov_2D_Re40").is_ok());
        let EnvInputError::UnknownEnv { closest, .. } = lookup("Cylinder_2D_Re10").unwrap_err() else {
            panic!("not an unknown-ID error")
        };
        assert_eq!(closest[0], "Cylinder_2D_Re100");
        assert!(matches!(lbm_spec("Kolmogorov_2D_Re40"), Err(EnvInputError::NotLbm { .. })));
    }

    #[test]
    fn every_family_registers_ids() {
        for f in FAMILIES {
            assert!(!f.specs().is_empty());
        }
    }

    #[test]
    fn committed_normalization_table_parses() {
        calibrate::parse_table(calibrate::TABLE).unwrap();
    }
}
