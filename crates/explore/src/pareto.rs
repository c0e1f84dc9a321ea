//! The multi-objective choice of Stage One (A§3.2.2, eq. 3.7–3.8): the Pareto
//! front of the contending viewpoints, the lowest sum of per-objective ranks
//! within it, and `f1` as the tie-break.

use geom::Real;

/// Whether an objective is minimised or maximised.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sense {
    /// Smaller is better (f1, f2, f3).
    Minimise,
    /// Larger is better (f4).
    Maximise,
}

/// `true` when `a` dominates `b`: at least as good in every objective and
/// better in one (eq. 3.8).
pub fn dominates(a: &[Real], b: &[Real], senses: &[Sense]) -> bool {
    let mut better = false;
    for ((x, y), s) in a.iter().zip(b).zip(senses) {
        let (x, y) = match s {
            Sense::Minimise => (*x, *y),
            Sense::Maximise => (-*x, -*y),
        };
        if x > y {
            return false;
        }
        better |= x < y;
    }
    better
}

/// Indices of the non-dominated rows of `f`, in index order.
pub fn pareto_front(f: &[Vec<Real>], senses: &[Sense]) -> Vec<usize> {
    (0..f.len())
        .filter(|&i| !(0..f.len()).any(|j| j != i && dominates(&f[j], &f[i], senses)))
        .collect()
}

/// Per-objective ranks of `front` (1 = best; equal values share the best
/// rank among them), summed per member.
pub fn rank_sums(f: &[Vec<Real>], front: &[usize], senses: &[Sense]) -> Vec<usize> {
    let mut sums = vec![0usize; front.len()];
    for (k, s) in senses.iter().enumerate() {
        let key = |i: usize| match s {
            Sense::Minimise => f[front[i]][k],
            Sense::Maximise => -f[front[i]][k],
        };
        for (i, sum) in sums.iter_mut().enumerate() {
            let better = (0..front.len()).filter(|&j| key(j) < key(i)).count();
            *sum += better + 1;
        }
    }
    sums
}

/// The choice of eq. 3.8's front: the lowest rank sum, then the lowest first
/// objective (f1), then the lowest index. `None` for no rows.
pub fn choose(f: &[Vec<Real>], senses: &[Sense]) -> Option<(usize, usize)> {
    let front = pareto_front(f, senses);
    let sums = rank_sums(f, &front, senses);
    front
        .iter()
        .zip(&sums)
        .min_by(|(a, sa), (b, sb)| {
            sa.cmp(sb)
                .then(f[**a][0].total_cmp(&f[**b][0]))
                .then(a.cmp(b))
        })
        .map(|(i, s)| (*i, *s))
}

#[cfg(test)]
mod tests {
    use super::*;

    const S: [Sense; 4] = [
        Sense::Minimise,
        Sense::Minimise,
        Sense::Minimise,
        Sense::Maximise,
    ];

    #[test]
    fn front_and_choice_by_hand() {
        let f = vec![
            vec![10.0, 5.0, 1.0, 2.0], // 0: on the front
            vec![9.0, 6.0, 2.0, 2.0],  // 1: on the front (best f1)
            vec![10.0, 5.0, 1.5, 1.5], // 2: dominated by 0
            vec![12.0, 4.0, 3.0, 5.0], // 3: on the front (best f2, f4)
            vec![10.0, 5.0, 1.0, 2.0], // 4: equal to 0: not dominated
        ];
        assert!(dominates(&f[0], &f[2], &S));
        assert!(!dominates(&f[0], &f[4], &S));
        let front = pareto_front(&f, &S);
        assert_eq!(front, vec![0, 1, 3, 4]);
        // Ranks on the front [0, 1, 3, 4]:
        //   f1: 10, 9, 12, 10 → 2, 1, 4, 2
        //   f2: 5, 6, 4, 5    → 2, 4, 1, 2
        //   f3: 1, 2, 3, 1    → 1, 3, 4, 1
        //   f4: 2, 2, 5, 2    → 2, 2, 1, 2
        assert_eq!(rank_sums(&f, &front, &S), vec![7, 10, 10, 7]);
        // 0 and 4 tie on rank sum and f1: the lower index wins.
        assert_eq!(choose(&f, &S), Some((0, 7)));
    }

    #[test]
    fn f1_breaks_a_tie_in_rank_sum() {
        let f = vec![vec![2.0, 1.0, 0.0, 1.0], vec![1.0, 2.0, 0.0, 1.0]];
        // Ranks: 0 → 2 + 1 + 1 + 1 = 5; 1 → 1 + 2 + 1 + 1 = 5.
        assert_eq!(choose(&f, &S), Some((1, 5)));
        assert_eq!(choose(&[], &S), None);
    }
}
