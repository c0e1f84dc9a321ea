//! The order in which a segment's targets are visited (Paul App. A.2): the
//! genetic algorithm of eq. A.6–A.10, and the nearest-neighbour order and
//! its 2-opt improvement it is compared with.
//!
//! # Cost (eq. A.6–A.9)
//!
//! Moving from target `j` to target `k` costs `g = α d + β m`, with `d` the
//! Euclidean distance between the targets' centres `P̂` (eq. A.7) and `m =
//! Σ_l |q_l,k − q_l,j|` the joint movement between their poses (eq. A.8); a
//! sequence costs the sum over its consecutive pairs (eq. A.9). The path is
//! open: it starts at its first target and ends at its last.
//!
//! # Weights (eq. A.10)
//!
//! The thesis computes the weights from the population's mean travel `μ_T`
//! and joint movement `μ_J` "to normalise the travel distance and joint
//! movement", and prints `α = μ_T / (μ_T + μ_J)`, `β = μ_J / (μ_T + μ_J)`.
//! As printed they do the opposite of normalising (the larger term is
//! weighted up); we read them swapped, `α = μ_J / (μ_T + μ_J)`, `β = μ_T /
//! (μ_T + μ_J)`, so that `α μ_T = β μ_J`: both terms weigh the same on
//! average ([`Weights::normalising`]). The GA recomputes them every
//! generation from its population; the three orders are compared on one
//! fixed cost ([`Weights`] of the nearest-neighbour order), which is the cost
//! [`genetic`] reports.
//!
//! # GA (App. A.2, Fig. A.2)
//!
//! A population of `n_cr` permutations, the first the initial plan (we give
//! it the 2-opt order: Paul's "educated guess for the search direction").
//! Every generation:
//!
//! 1. the weights of eq. A.10 from the population, and each chromosome's
//!    fitness (eq. A.9);
//! 2. a mating pool of `n_cr / 2` by tournament: the population is paired
//!    at random and the fitter of each pair kept;
//! 3. `n_cr / 4` reproduced by the same tournament over the mating pool;
//! 4. `n_cr / 4` children by crossover of random pairs from the mating pool
//!    (the thesis does not name the operator; order crossover, OX, keeps
//!    a child a permutation);
//! 5. the remaining `n_cr / 2` by mutating reproduced and child chromosomes,
//!    by one of the two kinds at random: two slots exchanged, or the slots
//!    between two random ones reversed;
//!
//! until the generation limit. The fittest chromosome wins every tournament
//! it enters, so it always survives. The best chromosome ever seen under the
//! fixed comparison cost is returned: never worse than the initial plan.

use geom::{Point3, Real};
use rand::{Rng, RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::{Deserialize, Serialize};

/// The targets of one sequence: their centres and the poses that reach them.
#[derive(Clone, Debug)]
pub struct Targets {
    n: usize,
    /// `d` between every pair, row-major.
    travel: Vec<Real>,
    /// `m` between every pair, row-major.
    joints: Vec<Real>,
}

impl Targets {
    /// The pairwise travel (eq. A.7) and joint movement (eq. A.8) of targets
    /// centred at `centres` and reached at `poses` (one joint vector each, all
    /// of one length). `None` when the counts or lengths disagree.
    pub fn new(centres: &[Point3], poses: &[Vec<Real>]) -> Option<Self> {
        let n = centres.len();
        if poses.len() != n || poses.windows(2).any(|w| w[0].len() != w[1].len()) {
            return None;
        }
        let mut travel = vec![0.0; n * n];
        let mut joints = vec![0.0; n * n];
        for j in 0..n {
            for k in 0..n {
                travel[j * n + k] = (centres[k] - centres[j]).norm();
                joints[j * n + k] = poses[j]
                    .iter()
                    .zip(&poses[k])
                    .map(|(a, b)| (b - a).abs())
                    .sum();
            }
        }
        Some(Self { n, travel, joints })
    }

    /// Number of targets.
    pub fn len(&self) -> usize {
        self.n
    }

    /// `true` without targets.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// `(Σ d, Σ m)` along `order` (eq. A.7–A.8 summed).
    pub fn totals(&self, order: &[usize]) -> (Real, Real) {
        order.windows(2).fold((0.0, 0.0), |(d, m), w| {
            let i = w[0] * self.n + w[1];
            (d + self.travel[i], m + self.joints[i])
        })
    }

    /// The cost of `order` under `w` (eq. A.9).
    pub fn cost(&self, order: &[usize], w: Weights) -> Real {
        w.cost_of(self.totals(order))
    }

    fn step(&self, a: usize, b: usize, w: Weights) -> Real {
        let i = a * self.n + b;
        w.alpha * self.travel[i] + w.beta * self.joints[i]
    }
}

/// The weights `α` (travel, per metre) and `β` (joint movement, per radian)
/// of eq. A.6.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Weights {
    /// Weight of the travel distance.
    pub alpha: Real,
    /// Weight of the joint movement.
    pub beta: Real,
}

impl Weights {
    /// Eq. A.10 as we read it (see the [module docs](self)): from mean travel
    /// `μ_T` and joint movement `μ_J`, `α = μ_J / (μ_T + μ_J)` and `β = μ_T /
    /// (μ_T + μ_J)`; equal weights when both are 0.
    pub fn normalising(mu_t: Real, mu_j: Real) -> Self {
        let sum = mu_t + mu_j;
        if sum > 0.0 && sum.is_finite() {
            Self {
                alpha: mu_j / sum,
                beta: mu_t / sum,
            }
        } else {
            Self {
                alpha: 0.5,
                beta: 0.5,
            }
        }
    }

    /// [`Weights::normalising`] of the mean totals of `orders`.
    pub fn of_population(targets: &Targets, orders: &[Vec<usize>]) -> Self {
        let totals: Vec<(Real, Real)> = orders.iter().map(|o| targets.totals(o)).collect();
        Self::of_totals(&totals)
    }

    /// [`Weights::of_population`] from the population's
    /// [`Targets::totals`], each computed once.
    fn of_totals(totals: &[(Real, Real)]) -> Self {
        let n = totals.len().max(1) as Real;
        let (d, m) = totals
            .iter()
            .fold((0.0, 0.0), |(d, m), (a, b)| (d + a, m + b));
        Self::normalising(d / n, m / n)
    }

    /// The cost (eq. A.9) of an order of these [`Targets::totals`]: what
    /// [`Targets::cost`] gives for it under these weights.
    fn cost_of(self, (d, m): (Real, Real)) -> Real {
        self.alpha * d + self.beta * m
    }
}

/// The nearest-neighbour order from target `start`: each next target is the
/// cheapest step under `w` from the last (ties: the lowest index).
pub fn nearest_neighbour(targets: &Targets, start: usize, w: Weights) -> Vec<usize> {
    let n = targets.len();
    if n == 0 {
        return Vec::new();
    }
    let mut used = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut at = start.min(n - 1);
    used[at] = true;
    order.push(at);
    for _ in 1..n {
        let next = (0..n)
            .filter(|&k| !used[k])
            .min_by(|&a, &b| {
                targets
                    .step(at, a, w)
                    .total_cmp(&targets.step(at, b, w))
                    .then(a.cmp(&b))
            })
            .unwrap_or(at);
        used[next] = true;
        order.push(next);
        at = next;
    }
    order
}

/// `order` improved by 2-opt under `w` until no reversal of a stretch of it
/// lowers the cost (open path: its first target stays first). The costs
/// are symmetric, so a reversal changes only the two steps at its ends.
pub fn two_opt(targets: &Targets, order: &[usize], w: Weights) -> Vec<usize> {
    let mut o = order.to_vec();
    let n = o.len();
    if n < 3 {
        return o;
    }
    loop {
        let mut improved = false;
        for i in 1..n - 1 {
            for j in i + 1..n {
                // Reverse o[i..=j]: the steps (i−1, i) and (j, j+1) change.
                let before = targets.step(o[i - 1], o[i], w)
                    + if j + 1 < n {
                        targets.step(o[j], o[j + 1], w)
                    } else {
                        0.0
                    };
                let after = targets.step(o[i - 1], o[j], w)
                    + if j + 1 < n {
                        targets.step(o[i], o[j + 1], w)
                    } else {
                        0.0
                    };
                if after < before - 1e-12 * before.abs().max(1.0) {
                    o[i..=j].reverse();
                    improved = true;
                }
            }
        }
        if !improved {
            return o;
        }
    }
}

/// Parameters of the GA (App. A.2).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct GaConfig {
    /// Population size `n_cr` (a multiple of 4 is used: rounded up).
    pub population: usize,
    /// Generation limit.
    pub generations: usize,
    /// Seed of every random choice.
    pub seed: u64,
}

impl Default for GaConfig {
    fn default() -> Self {
        Self {
            population: 40,
            generations: 1000,
            seed: 0,
        }
    }
}

/// What [`genetic`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct GaResult {
    /// The best order, under the comparison cost.
    pub order: Vec<usize>,
    /// Its cost under the comparison weights.
    pub cost: Real,
    /// The best comparison cost after each generation (non-increasing).
    pub history: Vec<Real>,
    /// The weights of eq. A.10 in the last generation.
    pub last_weights: Weights,
}

/// The GA of App. A.2 from `initial` (a permutation of the targets), its
/// result measured with the comparison weights `compare` (see the [module
/// docs](self)). Deterministic for a seed. Sequences of fewer than four
/// targets are returned as 2-opt leaves them.
pub fn genetic(targets: &Targets, initial: &[usize], compare: Weights, cfg: &GaConfig) -> GaResult {
    let n = initial.len();
    let mut best = initial.to_vec();
    let mut best_cost = targets.cost(&best, compare);
    if n < 4 || cfg.generations == 0 {
        return GaResult {
            order: best,
            cost: best_cost,
            history: Vec::new(),
            last_weights: compare,
        };
    }
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.seed);
    let size = cfg.population.max(4).div_ceil(4) * 4;
    // The initial plan, then mutations of it.
    let mut population: Vec<Vec<usize>> = vec![initial.to_vec()];
    while population.len() < size {
        let mut c = initial.to_vec();
        for _ in 0..=population.len() % 4 {
            mutate(&mut c, &mut rng);
        }
        population.push(c);
    }
    let mut history = Vec::with_capacity(cfg.generations);
    let mut weights = compare;
    // Each individual's totals once a generation: the weights, the fitness
    // and the best-so-far check all come from them.
    let mut totals: Vec<(Real, Real)> = population.iter().map(|c| targets.totals(c)).collect();
    for _ in 0..cfg.generations {
        weights = Weights::of_totals(&totals);
        let fitness: Vec<Real> = totals.iter().map(|&t| weights.cost_of(t)).collect();
        let pool = tournament(&(0..size).collect::<Vec<_>>(), &fitness, &mut rng);
        let reproduced = tournament(&pool, &fitness, &mut rng);
        let mut next: Vec<Vec<usize>> = reproduced.iter().map(|&i| population[i].clone()).collect();
        for _ in 0..size / 4 {
            let a = pool[rng.random_range(0..pool.len())];
            let b = pool[rng.random_range(0..pool.len())];
            next.push(order_crossover(&population[a], &population[b], &mut rng));
        }
        let parents = next.len();
        while next.len() < size {
            let mut c = next[rng.random_range(0..parents)].clone();
            mutate(&mut c, &mut rng);
            next.push(c);
        }
        population = next;
        totals = population.iter().map(|c| targets.totals(c)).collect();
        for (c, &t) in population.iter().zip(&totals) {
            let cost = compare.cost_of(t);
            if cost < best_cost {
                best_cost = cost;
                best.clone_from(c);
            }
        }
        history.push(best_cost);
    }
    GaResult {
        order: best,
        cost: best_cost,
        history,
        last_weights: weights,
    }
}

/// Pair `entrants` at random and keep the fitter (lower `fitness`) of each
/// pair: half of them (an odd one out is kept).
fn tournament<R: Rng + ?Sized>(entrants: &[usize], fitness: &[Real], rng: &mut R) -> Vec<usize> {
    let mut e = entrants.to_vec();
    shuffle(&mut e, rng);
    e.chunks(2)
        .map(|p| match p {
            [a, b] => {
                if fitness[*b] < fitness[*a] {
                    *b
                } else {
                    *a
                }
            }
            [a] => *a,
            _ => unreachable!("chunks of two"),
        })
        .collect()
}

fn shuffle<T, R: Rng + ?Sized>(v: &mut [T], rng: &mut R) {
    for i in (1..v.len()).rev() {
        let j = rng.random_range(0..=i);
        v.swap(i, j);
    }
}

/// One mutation, its kind drawn at random: exchange two slots, or reverse
/// the slots between two.
fn mutate<R: Rng + ?Sized>(c: &mut [usize], rng: &mut R) {
    let n = c.len();
    let (mut i, mut j) = (rng.random_range(0..n), rng.random_range(0..n));
    if i > j {
        std::mem::swap(&mut i, &mut j);
    }
    if rng.random_bool(0.5) {
        c.swap(i, j);
    } else {
        c[i..=j].reverse();
    }
}

/// Order crossover (OX): the child keeps a random stretch of `a` in place
/// and fills the other slots with the remaining targets in `b`'s order.
fn order_crossover<R: Rng + ?Sized>(a: &[usize], b: &[usize], rng: &mut R) -> Vec<usize> {
    let n = a.len();
    let (mut i, mut j) = (rng.random_range(0..n), rng.random_range(0..n));
    if i > j {
        std::mem::swap(&mut i, &mut j);
    }
    let mut taken = vec![false; n];
    for &t in &a[i..=j] {
        taken[t] = true;
    }
    let mut rest = b.iter().copied().filter(|&t| !taken[t]);
    (0..n)
        .map(|k| {
            if (i..=j).contains(&k) {
                a[k]
            } else {
                rest.next().unwrap_or(a[k])
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn is_permutation(o: &[usize], n: usize) -> bool {
        let mut s = o.to_vec();
        s.sort_unstable();
        s == (0..n).collect::<Vec<_>>()
    }

    #[test]
    fn cost_by_hand() {
        // Three targets 1 m apart on x, joint 1 at 0, 1, 0.5 rad.
        let c = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(1.0, 0.0, 0.0),
            Point3::new(2.0, 0.0, 0.0),
        ];
        let q = vec![vec![0.0, 0.0], vec![1.0, 0.0], vec![0.5, 0.0]];
        let t = Targets::new(&c, &q).unwrap();
        assert_eq!(t.totals(&[0, 1, 2]), (2.0, 1.5));
        assert_eq!(t.totals(&[0, 2, 1]), (3.0, 1.0));
        let w = Weights {
            alpha: 0.25,
            beta: 1.0,
        };
        assert!((t.cost(&[0, 2, 1], w) - (0.75 + 1.0)).abs() < 1e-12);
        // The normalising reading of eq. A.10: α μ_T = β μ_J, α + β = 1.
        let w = Weights::normalising(2.0, 6.0);
        assert!((w.alpha * 2.0 - w.beta * 6.0).abs() < 1e-12);
        assert!((w.alpha + w.beta - 1.0).abs() < 1e-12);
        assert!(Targets::new(&c, &q[..2]).is_none());
    }

    #[test]
    fn two_opt_straightens_a_line() {
        // Targets on a line, visited in a scrambled order from the left end:
        // the optimum is left to right.
        let xs = [0.0, 3.0, 1.0, 4.0, 2.0, 5.0];
        let c: Vec<Point3> = xs.iter().map(|&x| Point3::new(x, 0.0, 0.0)).collect();
        let q: Vec<Vec<Real>> = xs.iter().map(|&x| vec![0.1 * x]).collect();
        let t = Targets::new(&c, &q).unwrap();
        let w = Weights::normalising(1.0, 0.1);
        let o = two_opt(&t, &[0, 1, 2, 3, 4, 5], w);
        assert_eq!(o, vec![0, 2, 4, 1, 3, 5]);
        assert_eq!(nearest_neighbour(&t, 0, w), vec![0, 2, 4, 1, 3, 5]);
    }

    /// The cheapest open path through all targets, any start, by brute force.
    fn brute_force(t: &Targets, w: Weights) -> Real {
        fn go(t: &Targets, w: Weights, path: &mut Vec<usize>, used: &mut [bool], best: &mut Real) {
            if path.len() == used.len() {
                *best = best.min(t.cost(path, w));
                return;
            }
            for k in 0..used.len() {
                if !used[k] {
                    used[k] = true;
                    path.push(k);
                    go(t, w, path, used, best);
                    path.pop();
                    used[k] = false;
                }
            }
        }
        let mut best = Real::INFINITY;
        go(t, w, &mut Vec::new(), &mut vec![false; t.len()], &mut best);
        best
    }

    fn random_targets(n: usize, seed: u64) -> Targets {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let c: Vec<Point3> = (0..n)
            .map(|_| Point3::new(rng.random_range(0.0..1.0), rng.random_range(0.0..1.0), 0.0))
            .collect();
        let q: Vec<Vec<Real>> = c
            .iter()
            .map(|p| {
                (0..6)
                    .map(|l| p.x * (l as Real) - p.y + rng.random_range(-0.05..0.05))
                    .collect()
            })
            .collect();
        Targets::new(&c, &q).unwrap()
    }

    #[test]
    fn ga_reaches_the_brute_force_optimum_on_small_sets() {
        for seed in 0..3 {
            let t = random_targets(8, seed);
            let nn = nearest_neighbour(&t, 0, Weights::normalising(1.0, 1.0));
            let w = Weights::of_population(&t, std::slice::from_ref(&nn));
            let opt = two_opt(&t, &nn, w);
            // The GA may start anywhere: brute force over every start.
            let best = brute_force(&t, w);
            let ga = genetic(
                &t,
                &opt,
                w,
                &GaConfig {
                    seed,
                    ..GaConfig::default()
                },
            );
            assert!(is_permutation(&ga.order, 8));
            assert!((ga.cost - t.cost(&ga.order, w)).abs() < 1e-12);
            assert!(ga.cost <= t.cost(&opt, w) + 1e-12);
            assert!(t.cost(&opt, w) <= t.cost(&nn, w) + 1e-12);
            assert!(ga.cost >= best - 1e-12);
            assert!(
                ga.cost <= best + 1e-9,
                "seed {seed}: GA {} vs optimum {best}",
                ga.cost
            );
            assert!(ga.history.windows(2).all(|h| h[1] <= h[0]));
        }
    }

    #[test]
    fn ga_improves_on_two_opt_and_is_deterministic() {
        let t = random_targets(120, 7);
        let nn0 = nearest_neighbour(&t, 0, Weights::normalising(1.0, 1.0));
        let w = Weights::of_population(&t, std::slice::from_ref(&nn0));
        let nn = nearest_neighbour(&t, 0, w);
        let opt = two_opt(&t, &nn, w);
        let cfg = GaConfig {
            seed: 3,
            ..GaConfig::default()
        };
        let a = genetic(&t, &opt, w, &cfg);
        let b = genetic(&t, &opt, w, &cfg);
        assert_eq!(a, b);
        assert!(is_permutation(&a.order, 120));
        let (c_nn, c_opt) = (t.cost(&nn, w), t.cost(&opt, w));
        assert!(c_opt < c_nn, "2-opt {c_opt} vs NN {c_nn}");
        assert!(a.cost < c_opt, "GA {} vs 2-opt {c_opt}", a.cost);
    }

    #[test]
    fn crossover_and_mutation_keep_permutations() {
        let mut rng = ChaCha8Rng::seed_from_u64(1);
        let a: Vec<usize> = (0..30).collect();
        let mut b = a.clone();
        shuffle(&mut b, &mut rng);
        for _ in 0..200 {
            let mut c = order_crossover(&a, &b, &mut rng);
            assert!(is_permutation(&c, 30));
            mutate(&mut c, &mut rng);
            assert!(is_permutation(&c, 30));
        }
    }
}
