//! Every environment ID and its spec.

use super::calibrate;
use super::cavity;
use super::cylinder;
use super::naca;
use super::pinball;
use super::pipe;
use super::spec::EnvSpec;
use super::square;

/// All registered specs, in a fixed order, with their committed observation statistics.
pub fn all() -> Vec<EnvSpec> {
    let mut v = Vec::new();
    for re in cylinder::REYNOLDS {
        v.push(cylinder::jets(re));
    }
    for re in cylinder::REYNOLDS {
        v.push(cylinder::rotary(re));
    }
    for re in pinball::REYNOLDS {
        v.push(pinball::rotary(re));
    }
    for re in pinball::REYNOLDS {
        v.push(pinball::jets(re));
    }
    for re in square::REYNOLDS {
        v.push(square::square(re));
    }
    v.extend(cavity::specs());
    for re in naca::REYNOLDS {
        for aoa in naca::ANGLES {
            v.push(naca::steady(re, aoa));
        }
    }
    for re in naca::REYNOLDS {
        for aoa in naca::ANGLES {
            v.extend(naca::gust(re, aoa));
        }
    }
    for re in pipe::REYNOLDS {
        v.push(pipe::stenotic_pipe(re));
    }
    // The table is checked by a test; a broken one only means uncalibrated observations.
    for s in &mut v {
        calibrate::attach(s, calibrate::table());
    }
    v
}

/// The spec of `id`, or the list of IDs (closest first) to put in the error.
pub fn get(id: &str) -> Result<EnvSpec, Vec<String>> {
    let specs = all();
    if let Some(s) = specs.iter().find(|s| s.id == id) {
        return Ok(s.clone());
    }
    let mut ids: Vec<(usize, String)> = specs
        .into_iter()
        .map(|s| (edit_distance(&s.id.to_lowercase(), &id.to_lowercase()), s.id))
        .collect();
    ids.sort();
    Err(ids.into_iter().map(|(_, id)| id).collect())
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
        let mut ids: Vec<&str> = specs.iter().map(|s| s.id.as_str()).collect();
        ids.sort();
        ids.dedup();
        assert_eq!(ids.len(), specs.len());
        assert!(get("Cylinder_2D_Re100").is_ok());
        let err = get("Cylinder_2D_Re10").unwrap_err();
        assert_eq!(err[0], "Cylinder_2D_Re100");
    }

    #[test]
    fn committed_normalization_table_parses() {
        calibrate::parse_table(calibrate::TABLE).unwrap();
    }
}
