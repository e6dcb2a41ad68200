//! Facets: which curves share a panel. One panel per temperature; a temperature with more
//! than [`MAX_PER_PANEL`] curves is split into groups of neighbouring stresses (replicates
//! of one stress stay together), so that every panel holds a few curves of similar life
//! that can be told apart.

use super::CurveId;

/// Most curves drawn in one panel.
pub const MAX_PER_PANEL: usize = 6;

/// Most measured points a plot draws per curve (thinned evenly beyond).
pub const PLOT_POINTS: usize = 2000;

/// One panel: its caption and the indices of its curves (ascending stress, then specimen).
#[derive(Debug, Clone, PartialEq)]
pub struct Facet {
    pub caption: String,
    pub members: Vec<usize>,
}

/// The panels of `ids`, in ascending temperature, then ascending stress: every index in
/// exactly one panel, at most `max` (≥ 1) per panel unless more than `max` replicates share
/// one stress (those are split by specimen order). A panel's caption is its temperature, and
/// its stress range when the temperature is split.
pub fn facets(ids: &[CurveId], max: usize) -> Vec<Facet> {
    let max = max.max(1);
    let mut order: Vec<usize> = (0..ids.len()).collect();
    order.sort_by(|&a, &b| {
        let (p, q) = (&ids[a], &ids[b]);
        p.temperature_c
            .total_cmp(&q.temperature_c)
            .then(p.stress_mpa.total_cmp(&q.stress_mpa))
            .then(p.specimen.cmp(&q.specimen))
            .then(a.cmp(&b))
    });
    let same = |a: f64, b: f64| a.total_cmp(&b).is_eq();
    let mut out = Vec::new();
    for group in runs(&order, |a, b| {
        same(ids[a].temperature_c, ids[b].temperature_c)
    }) {
        let t = ids[group[0]].temperature_c;
        if group.len() <= max {
            out.push(Facet {
                caption: format!("{t} °C"),
                members: group,
            });
            continue;
        }
        for members in split_by_stress(ids, &group, max) {
            let (lo, hi) = (
                ids[members[0]].stress_mpa,
                ids[*members.last().expect("non-empty")].stress_mpa,
            );
            let stresses = if same(lo, hi) {
                format!("{lo} MPa")
            } else {
                format!("{lo}–{hi} MPa")
            };
            out.push(Facet {
                caption: format!("{t} °C, {stresses}"),
                members,
            });
        }
    }
    out
}

/// Consecutive runs of `order` whose neighbours are `equal`.
fn runs(order: &[usize], equal: impl Fn(usize, usize) -> bool) -> Vec<Vec<usize>> {
    let mut out: Vec<Vec<usize>> = Vec::new();
    for &i in order {
        match out.last_mut() {
            Some(run) if equal(run[0], i) => run.push(i),
            _ => out.push(vec![i]),
        }
    }
    out
}

/// `group` (one temperature, ascending stress) in consecutive stress groups of about equal
/// size: ⌈n / ⌈n / max⌉⌉ curves each, a stress level never divided unless it alone holds more
/// than `max` curves.
fn split_by_stress(ids: &[CurveId], group: &[usize], max: usize) -> Vec<Vec<usize>> {
    let n = group.len();
    let panels = n.div_ceil(max);
    let cap = n.div_ceil(panels);
    let levels = runs(group, |a, b| {
        ids[a].stress_mpa.total_cmp(&ids[b].stress_mpa).is_eq()
    });
    let mut out: Vec<Vec<usize>> = Vec::new();
    let mut current: Vec<usize> = Vec::new();
    for level in levels {
        if !current.is_empty() && current.len() + level.len() > cap {
            out.push(std::mem::take(&mut current));
        }
        if level.len() > max {
            out.extend(level.chunks(max).map(|c| c.to_vec()));
        } else {
            current.extend(level);
        }
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    fn id(t: f64, s: f64, sp: &str) -> CurveId {
        CurveId {
            temperature_c: t,
            stress_mpa: s,
            specimen: (!sp.is_empty()).then(|| sp.to_string()),
        }
    }

    /// The 34 Alloy 617 tests (data/alloy617/ruptures_alloy617.csv), in file order.
    pub(crate) fn alloy617() -> Vec<CurveId> {
        let rows: &[(f64, f64, &str)] = &[
            (750.0, 118.0, "INL2-a"),
            (750.0, 118.0, "INL2-b"),
            (750.0, 137.0, "INL2-a"),
            (750.0, 137.0, "INL2-b"),
            (750.0, 95.0, "INL2-a"),
            (850.0, 43.0, "INL2-a"),
            (850.0, 43.0, "INL2-b"),
            (850.0, 54.0, "INL2-a"),
            (850.0, 54.0, "INL2-b"),
            (850.0, 63.0, "INL2-a"),
            (850.0, 63.0, "INL2-b"),
            (850.0, 30.0, "KAERI2-a"),
            (850.0, 35.0, "KAERI2-a"),
            (850.0, 40.0, "KAERI2-a"),
            (850.0, 45.0, "KAERI2-a"),
            (850.0, 50.0, "KAERI2-a"),
            (850.0, 60.0, "KAERI2-a"),
            (850.0, 70.0, "KAERI2-a"),
            (900.0, 25.0, "KAERI2-a"),
            (900.0, 28.0, "KAERI2-a"),
            (900.0, 30.0, "KAERI2-a"),
            (900.0, 35.0, "KAERI2-a"),
            (900.0, 40.0, "KAERI2-a"),
            (900.0, 45.0, "KAERI2-a"),
            (900.0, 50.0, "KAERI2-a"),
            (950.0, 19.0, "INL2-a"),
            (950.0, 24.0, "INL2-a"),
            (950.0, 29.0, "INL2-a"),
            (950.0, 29.0, "INL2-b"),
            (950.0, 18.0, "KAERI2-a"),
            (950.0, 20.0, "KAERI2-a"),
            (950.0, 22.0, "KAERI2-a"),
            (950.0, 30.0, "KAERI2-a"),
            (950.0, 35.0, "KAERI2-a"),
        ];
        rows.iter().map(|&(t, s, sp)| id(t, s, sp)).collect()
    }

    /// Every index exactly once, at most `max` per panel, one temperature per panel, panels
    /// in ascending temperature and stress.
    fn check(ids: &[CurveId], f: &[Facet], max: usize) {
        let mut all: Vec<usize> = f.iter().flat_map(|p| p.members.clone()).collect();
        all.sort();
        assert_eq!(all, (0..ids.len()).collect::<Vec<_>>(), "{f:?}");
        for p in f {
            assert!(!p.members.is_empty() && p.members.len() <= max, "{p:?}");
            let t = ids[p.members[0]].temperature_c;
            assert!(p.members.iter().all(|&i| ids[i].temperature_c == t));
            assert!(p.caption.starts_with(&format!("{t} °C")), "{}", p.caption);
        }
        let keys: Vec<(f64, f64)> = f
            .iter()
            .flat_map(|p| {
                p.members
                    .iter()
                    .map(|&i| (ids[i].temperature_c, ids[i].stress_mpa))
            })
            .collect();
        assert!(keys.windows(2).all(|w| w[0] <= w[1]), "{keys:?}");
    }

    #[test]
    fn alloy617_in_eight_panels() {
        let ids = alloy617();
        let f = facets(&ids, MAX_PER_PANEL);
        check(&ids, &f, MAX_PER_PANEL);
        let captions: Vec<&str> = f.iter().map(|p| p.caption.as_str()).collect();
        assert_eq!(
            captions,
            [
                "750 °C",
                "850 °C, 30–43 MPa",
                "850 °C, 45–60 MPa",
                "850 °C, 63–70 MPa",
                "900 °C, 25–35 MPa",
                "900 °C, 40–50 MPa",
                "950 °C, 18–24 MPa",
                "950 °C, 29–35 MPa",
            ]
        );
        let sizes: Vec<usize> = f.iter().map(|p| p.members.len()).collect();
        assert_eq!(sizes, [5, 5, 5, 3, 4, 3, 5, 4]);
        // Replicates of one stress share a panel.
        for p in &f {
            for &i in &p.members {
                for (j, other) in ids.iter().enumerate() {
                    if other.temperature_c == ids[i].temperature_c
                        && other.stress_mpa == ids[i].stress_mpa
                    {
                        assert!(p.members.contains(&j), "{} split", ids[i].stress_mpa);
                    }
                }
            }
        }
    }

    #[test]
    fn one_temperature_in_stress_groups() {
        let ids: Vec<CurveId> = alloy617()
            .into_iter()
            .filter(|i| i.temperature_c == 850.0)
            .collect();
        let f = facets(&ids, MAX_PER_PANEL);
        check(&ids, &f, MAX_PER_PANEL);
        assert_eq!(f.len(), 3);
        // Few curves: one panel, captioned with the temperature alone.
        let few = &ids[..4];
        let f = facets(few, MAX_PER_PANEL);
        assert_eq!(f.len(), 1);
        assert_eq!(f[0].caption, "850 °C");
        assert_eq!(f[0].members.len(), 4);
    }

    #[test]
    fn edge_cases() {
        assert!(facets(&[], 6).is_empty());
        // Eight replicates at one stress: split, never more than max per panel.
        let ids: Vec<CurveId> = (0..8).map(|i| id(600.0, 100.0, &format!("S{i}"))).collect();
        let f = facets(&ids, 3);
        check(&ids, &f, 3);
        assert_eq!(f.len(), 3);
        assert!(f.iter().all(|p| p.caption == "600 °C, 100 MPa"));
        // Non-finite values are grouped, not lost.
        let ids = vec![
            id(f64::NAN, 1.0, ""),
            id(500.0, f64::NAN, ""),
            id(500.0, 2.0, ""),
        ];
        let f = facets(&ids, 6);
        let n: usize = f.iter().map(|p| p.members.len()).sum();
        assert_eq!(n, 3);
        // max = 0 behaves as 1.
        let f = facets(&alloy617()[..3], 0);
        assert_eq!(f.len(), 3);
    }
}
