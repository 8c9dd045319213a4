//! Vector quantisation of SH transfer vectors (the Ca3D-Engine thesis §5.6.1, digest §1.6): Lloyd's algorithm
//! ("Iterated Closest Points") with the seed's termination on the largest nearest-neighbour
//! distance, so that every texel can store a 16-bit index into a table of representatives.

use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::hash::{Hash, Hasher};

use super::storage::MAX_REPS;

/// CAFU's initial "previous error": any first error below it counts as an improvement.
const INITIAL_PREVIOUS_ERROR: f64 = 1000.0;

/// Below this much work per pass (vectors × representatives × dimension) one thread is faster
/// than spawning several.
const PARALLEL_WORK: usize = 1 << 18;

/// Parameters of [`quantize`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct VqSettings {
    /// Representatives |R| wanted, 1..=65536 (16-bit indices). Fewer are used when there are
    /// fewer distinct vectors.
    pub reps: usize,
    /// Safety cap on assignment passes; the seed's criterion normally stops long before.
    pub max_iterations: usize,
    /// Consecutive passes without a decrease of the error after which to stop (the seed: 3).
    pub strikes: usize,
}

impl VqSettings {
    /// The seed's termination (3 strikes) with a cap of 100 passes.
    pub fn new(reps: usize) -> VqSettings {
        VqSettings {
            reps,
            max_iterations: 100,
            strikes: 3,
        }
    }
}

impl Default for VqSettings {
    /// 4096 representatives, the seed's smallest typical size.
    fn default() -> VqSettings {
        VqSettings::new(4096)
    }
}

/// Everything [`quantize`] can reject.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum VqError {
    #[error("representative count {0} is outside 1..={MAX_REPS} (indices are 16 bits)")]
    Reps(usize),
    #[error("vector dimension must be at least 1")]
    Dim,
    #[error("{len} values are not a whole number of {dim}-dimensional vectors")]
    Length { len: usize, dim: usize },
    #[error("there are no vectors to quantise")]
    Empty,
    #[error("vector {0} has a NaN or infinite component")]
    NonFinite(usize),
    #[error("{0} must be at least 1")]
    Setting(&'static str),
}

/// The result of [`quantize`].
#[derive(Clone, Debug, PartialEq)]
pub struct Quantized {
    /// Vector dimension (n² for n bands).
    pub dim: usize,
    /// Representatives, `reps()·dim` values, representative-major.
    pub codebook: Vec<f32>,
    /// Per vector, its nearest representative in `codebook` (lowest index on ties).
    pub indices: Vec<u16>,
    /// Assignment passes run; the last one produced `indices` from the final `codebook`.
    pub iterations: usize,
    /// Per pass, the largest squared distance of a vector to its representative: the seed's error.
    pub max_distance: Vec<f64>,
    /// Per pass, the sum of squared distances of the vectors to their representatives.
    pub sse: Vec<f64>,
    /// Representatives no vector uses in the final assignment (empty clusters keep their value).
    pub unused: usize,
}

impl Quantized {
    /// Representatives in the codebook: the requested count, or fewer when there were fewer
    /// vectors or fewer distinct vectors.
    pub fn reps(&self) -> usize {
        self.codebook.len() / self.dim
    }

    /// The final error (largest squared nearest distance).
    pub fn error(&self) -> f64 {
        self.max_distance.last().copied().unwrap_or(0.0)
    }
}

/// Quantises `vectors` (texel-major, `dim` values each) to at most `settings.reps`
/// representatives. `progress(pass, error)` is called after every assignment pass.
///
/// The seed's algorithm (§5.6.1): start from evenly strided picks `O[k·⌊S/|R|⌋]`, then repeat
/// "assign every vector to its nearest representative; replace each representative by its
/// cluster's mean", an empty cluster keeping its old value. It stops once the largest nearest
/// distance has failed to decrease `strikes` times in a row (previous error initially 1000, as
/// CAFU), because "assignments unchanged" can take hundreds of passes or cycle forever. It also
/// stops when that error is 0, which nothing can improve.
///
/// penumbra's choice: when there are no more distinct vectors than representatives, the
/// codebook is exactly the distinct vectors (error 0 in one pass). The seed's strided picks can
/// land on duplicates there and leave error the codebook could have avoided.
///
/// Passes end with an assignment, so `indices` always refer to the returned `codebook`. The
/// nearest search is a linear scan like CAFU's, split over threads; every vector's result is
/// independent of the split, so the output does not depend on the thread count.
pub fn quantize(
    vectors: &[f32],
    dim: usize,
    settings: &VqSettings,
    mut progress: impl FnMut(usize, f64),
) -> Result<Quantized, VqError> {
    validate(vectors, dim, settings)?;
    if let Some((codebook, indices)) = distinct_codebook(vectors, dim, settings.reps) {
        progress(0, 0.0);
        return Ok(Quantized {
            dim,
            codebook,
            indices,
            iterations: 1,
            max_distance: vec![0.0],
            sse: vec![0.0],
            unused: 0,
        });
    }
    let mut codebook = strided_codebook(vectors, dim, settings.reps);
    let mut q = Quantized {
        dim,
        codebook: Vec::new(),
        indices: Vec::new(),
        iterations: 0,
        max_distance: Vec::new(),
        sse: Vec::new(),
        unused: 0,
    };
    let (mut previous, mut strikes) = (INITIAL_PREVIOUS_ERROR, 0);
    loop {
        let (indices, distances) = assign(vectors, dim, &codebook);
        // Summed in vector order, so the totals do not depend on the thread split either.
        let error = distances.iter().copied().fold(0.0, f64::max);
        q.sse.push(distances.iter().sum());
        q.max_distance.push(error);
        progress(q.iterations, error);
        q.iterations += 1;
        strikes = if error < previous { 0 } else { strikes + 1 };
        previous = error;
        if strikes >= settings.strikes || error == 0.0 || q.iterations >= settings.max_iterations {
            q.unused = unused(&indices, codebook.len() / dim);
            q.indices = indices;
            q.codebook = codebook;
            return Ok(q);
        }
        update_means(vectors, dim, &indices, &mut codebook);
    }
}

fn validate(vectors: &[f32], dim: usize, settings: &VqSettings) -> Result<(), VqError> {
    if !(1..=MAX_REPS).contains(&settings.reps) {
        return Err(VqError::Reps(settings.reps));
    }
    if settings.max_iterations == 0 {
        return Err(VqError::Setting("max_iterations"));
    }
    if settings.strikes == 0 {
        return Err(VqError::Setting("strikes"));
    }
    if dim == 0 {
        return Err(VqError::Dim);
    }
    if !vectors.len().is_multiple_of(dim) {
        return Err(VqError::Length {
            len: vectors.len(),
            dim,
        });
    }
    if vectors.is_empty() {
        return Err(VqError::Empty);
    }
    // NaN would make every distance comparison false and the means NaN; infinities, NaN means.
    match vectors.chunks_exact(dim).position(|v| v.iter().any(|c| !c.is_finite())) {
        Some(bad) => Err(VqError::NonFinite(bad)),
        None => Ok(()),
    }
}

/// A vector as a hash key: equal when `==` holds componentwise (so −0 equals +0; NaN is
/// rejected before), which is exactly "at squared distance 0".
struct Key<'a>(&'a [f32]);

impl PartialEq for Key<'_> {
    fn eq(&self, other: &Self) -> bool {
        self.0 == other.0
    }
}

impl Eq for Key<'_> {}

impl Hash for Key<'_> {
    fn hash<H: Hasher>(&self, state: &mut H) {
        // Adding +0 turns −0 into +0, so equal vectors hash alike.
        self.0.iter().for_each(|c| (c + 0.0).to_bits().hash(state));
    }
}

/// The distinct vectors in first-occurrence order and every vector's index among them, or
/// `None` as soon as there are more than `reps` (then only `reps + 1` keys were ever held).
fn distinct_codebook(vectors: &[f32], dim: usize, reps: usize) -> Option<(Vec<f32>, Vec<u16>)> {
    let mut seen: HashMap<Key, u16> = HashMap::new();
    let mut codebook = Vec::new();
    let mut indices = Vec::with_capacity(vectors.len() / dim);
    for v in vectors.chunks_exact(dim) {
        let next = seen.len();
        let index = match seen.entry(Key(v)) {
            Entry::Occupied(e) => *e.get(),
            Entry::Vacant(_) if next >= reps => return None,
            Entry::Vacant(e) => {
                codebook.extend_from_slice(v);
                // next < reps ≤ MAX_REPS.
                *e.insert(next as u16)
            }
        };
        indices.push(index);
    }
    Some((codebook, indices))
}

/// The seed's initial codebook: `O[k·⌊S/|R|⌋]` for k < |R| = min(reps, S).
fn strided_codebook(vectors: &[f32], dim: usize, reps: usize) -> Vec<f32> {
    let count = vectors.len() / dim;
    let reps = reps.min(count);
    let stride = count / reps;
    (0..reps)
        .flat_map(|k| &vectors[k * stride * dim..(k * stride + 1) * dim])
        .copied()
        .collect()
}

/// Every vector's nearest representative (lowest index on ties) and its squared distance.
fn assign(vectors: &[f32], dim: usize, codebook: &[f32]) -> (Vec<u16>, Vec<f64>) {
    let count = vectors.len() / dim;
    let mut indices = vec![0u16; count];
    let mut distances = vec![0.0f64; count];
    let work = count.saturating_mul(codebook.len());
    let threads = if work < PARALLEL_WORK {
        1
    } else {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    };
    let chunk = count.div_ceil(threads).max(1);
    if threads == 1 {
        assign_range(vectors, dim, codebook, &mut indices, &mut distances);
    } else {
        std::thread::scope(|scope| {
            let parts = vectors
                .chunks(chunk * dim)
                .zip(indices.chunks_mut(chunk).zip(distances.chunks_mut(chunk)));
            for (part, (idx, dist)) in parts {
                scope.spawn(move || assign_range(part, dim, codebook, idx, dist));
            }
        });
    }
    (indices, distances)
}

fn assign_range(vectors: &[f32], dim: usize, codebook: &[f32], indices: &mut [u16], distances: &mut [f64]) {
    for ((v, index), distance) in vectors.chunks_exact(dim).zip(indices).zip(distances) {
        let mut best = (0, f32::INFINITY);
        for (r, rep) in codebook.chunks_exact(dim).enumerate() {
            let d = squared_distance_below(v, rep, best.1);
            // Strict: a later representative at the same distance never wins (ties → lowest).
            if d < best.1 {
                best = (r, d);
            }
        }
        // r < MAX_REPS (validated), so it fits 16 bits.
        *index = best.0 as u16;
        // The search compares in f32 for speed; the reported errors are recomputed in f64 so
        // the SSE the tests assert on is not f32 rounding noise.
        let rep = &codebook[best.0 * dim..(best.0 + 1) * dim];
        *distance = v
            .iter()
            .zip(rep)
            .map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2))
            .sum();
    }
}

/// Squared Euclidean distance, abandoned (returning something ≥ `bound`) once a partial sum
/// reaches `bound`. Partial sums of non-negative terms never decrease, even rounded, so an
/// abandoned candidate could not have been strictly nearer: the result of the nearest search is
/// that of a full scan, only faster. Groups of four keep the inner loop vectorisable.
fn squared_distance_below(a: &[f32], b: &[f32], bound: f32) -> f32 {
    let mut sum = 0.0f32;
    let groups = a.len() / 4;
    // Indexed fixed-size groups: about 25% faster at the dev profile's opt-level 1 than zipped
    // `chunks_exact`/`as_chunks` iterators, which it does not fully inline. The conversions
    // cannot fail (both slices are 4 long).
    for g in 0..groups {
        let (x, y): (&[f32; 4], &[f32; 4]) = (
            a[4 * g..4 * g + 4].try_into().unwrap(),
            b[4 * g..4 * g + 4].try_into().unwrap(),
        );
        let d = [x[0] - y[0], x[1] - y[1], x[2] - y[2], x[3] - y[3]];
        sum += (d[0] * d[0] + d[1] * d[1]) + (d[2] * d[2] + d[3] * d[3]);
        if sum >= bound {
            return sum;
        }
    }
    for i in 4 * groups..a.len() {
        sum += (a[i] - b[i]) * (a[i] - b[i]);
    }
    sum
}

/// Replaces each representative by the mean of its cluster (accumulated in f64, in vector order,
/// so deterministic); an empty cluster keeps its old value, as CAFU does.
fn update_means(vectors: &[f32], dim: usize, indices: &[u16], codebook: &mut [f32]) {
    let reps = codebook.len() / dim;
    let mut sums = vec![0.0f64; reps * dim];
    let mut counts = vec![0u32; reps];
    for (v, &i) in vectors.chunks_exact(dim).zip(indices) {
        let i = usize::from(i);
        counts[i] += 1;
        sums[i * dim..(i + 1) * dim]
            .iter_mut()
            .zip(v)
            .for_each(|(s, &c)| *s += f64::from(c));
    }
    for ((rep, sum), &count) in codebook.chunks_exact_mut(dim).zip(sums.chunks_exact(dim)).zip(&counts) {
        if count > 0 {
            rep.iter_mut()
                .zip(sum)
                .for_each(|(c, &s)| *c = (s / f64::from(count)) as f32);
        }
    }
}

fn unused(indices: &[u16], reps: usize) -> usize {
    let mut used = vec![false; reps];
    indices.iter().for_each(|&i| used[usize::from(i)] = true);
    used.iter().filter(|&&u| !u).count()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64*: reproducible test data.
    struct Rng(u64);

    impl Rng {
        fn next_u64(&mut self) -> u64 {
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
        }

        /// Uniform in [−1, 1).
        fn signed(&mut self) -> f32 {
            (self.next_u64() >> 40) as f32 / (1u64 << 23) as f32 - 1.0
        }
    }

    fn run(vectors: &[f32], dim: usize, settings: &VqSettings) -> Quantized {
        quantize(vectors, dim, settings, |_, _| {}).unwrap()
    }

    /// Checks the invariants every result must satisfy: the indices are the nearest (lowest on
    /// ties) representatives of the returned codebook, and the last pass's errors are theirs.
    fn assert_consistent(vectors: &[f32], dim: usize, q: &Quantized) {
        assert_eq!(q.indices.len(), vectors.len() / dim);
        assert_eq!((q.max_distance.len(), q.sse.len()), (q.iterations, q.iterations));
        let (mut sse, mut max) = (0.0f64, 0.0f64);
        for (v, &i) in vectors.chunks_exact(dim).zip(&q.indices) {
            let d = |r: usize| {
                v.iter()
                    .zip(&q.codebook[r * dim..(r + 1) * dim])
                    .map(|(&a, &b)| (f64::from(a) - f64::from(b)).powi(2))
                    .sum::<f64>()
            };
            let nearest = (0..q.reps()).map(d).fold(f64::INFINITY, f64::min);
            let first = (0..q.reps()).find(|&r| d(r) == nearest).unwrap();
            // The search compares in f32, so allow its rounding before insisting on the lowest index.
            assert!(
                d(usize::from(i)) <= nearest * (1.0 + 1e-5) + 1e-12,
                "vector {v:?} is not at its nearest representative"
            );
            if d(usize::from(i)) == nearest {
                assert_eq!(usize::from(i), first, "tie not resolved to the lowest index");
            }
            sse += d(usize::from(i));
            max = max.max(d(usize::from(i)));
        }
        assert!((sse - q.sse.last().unwrap()).abs() <= 1e-9 * sse.max(1e-30));
        assert_eq!(max, q.error());
        assert_eq!(
            q.unused,
            (0..q.reps()).filter(|&r| !q.indices.contains(&(r as u16))).count()
        );
    }

    #[test]
    fn error_is_exactly_zero_when_reps_cover_the_distinct_vectors() {
        let mut rng = Rng(0x1234_5678_9abc_def1);
        let dim = 16;
        let distinct: Vec<f32> = (0..50 * dim).map(|_| rng.signed()).collect();
        // 600 vectors cycling through the 50; the seed's stride-12 picks would take only every
        // other one (gcd(12, 50) = 2) and leave error.
        let vectors: Vec<f32> = (0..600)
            .flat_map(|i| &distinct[(i % 50) * dim..(i % 50 + 1) * dim])
            .copied()
            .collect();
        for reps in [50, 64, 4096] {
            let q = run(&vectors, dim, &VqSettings::new(reps));
            assert_eq!(q.reps(), 50, "reps {reps}");
            assert_eq!(
                (q.error(), *q.sse.last().unwrap(), q.unused),
                (0.0, 0.0, 0),
                "reps {reps}"
            );
            for (v, &i) in vectors.chunks_exact(dim).zip(&q.indices) {
                assert_eq!(v, &q.codebook[usize::from(i) * dim..(usize::from(i) + 1) * dim]);
            }
            assert_consistent(&vectors, dim, &q);
        }
        // −0 and +0 are the same vector: no representative is spent telling them apart.
        let q = run(&[0.0, -0.0, 1.0], 1, &VqSettings::new(2));
        assert_eq!((q.reps(), q.error()), (2, 0.0));
    }

    #[test]
    fn sse_never_increases_and_falls() {
        let mut rng = Rng(0xdead_beef_cafe_f00d);
        let dim = 16;
        // Clustered data (64 centres, noise 0.1) so Lloyd has something to improve for many passes.
        let centres: Vec<f32> = (0..64 * dim).map(|_| rng.signed()).collect();
        let vectors: Vec<f32> = (0..3000)
            .flat_map(|i| centres[(i * 7 % 64) * dim..(i * 7 % 64 + 1) * dim].to_vec())
            .map(|c| c + 0.1 * rng.signed())
            .collect();
        // Many strikes so that SSE is followed well past the seed's stop.
        let q = run(
            &vectors,
            dim,
            &VqSettings {
                reps: 48,
                max_iterations: 60,
                strikes: 20,
            },
        );
        assert!(q.iterations >= 5, "only {} passes", q.iterations);
        for (i, pair) in q.sse.windows(2).enumerate() {
            assert!(
                pair[1] <= pair[0] * (1.0 + 1e-9),
                "SSE rose at pass {}: {} → {}",
                i + 1,
                pair[0],
                pair[1]
            );
        }
        // Non-increasing alone would pass with representatives that never move.
        assert!(*q.sse.last().unwrap() < 0.8 * q.sse[0], "SSE {:?}", q.sse);
        assert_consistent(&vectors, dim, &q);
    }

    #[test]
    fn stops_after_three_strikes_on_tie_heavy_data() {
        // Points of a square lattice plus its cell centres: many vectors equidistant from two or
        // four representatives, the situation where "assignments unchanged" can cycle.
        let mut vectors = Vec::new();
        for y in 0..12 {
            for x in 0..12 {
                vectors.extend([x as f32, y as f32, x as f32 + 0.5, y as f32 + 0.5]);
            }
        }
        for reps in [2, 3, 4, 7, 16, 33] {
            let settings = VqSettings {
                reps,
                max_iterations: 1000,
                strikes: 3,
            };
            let mut reported = Vec::new();
            let q = quantize(&vectors, 2, &settings, |pass, error| reported.push((pass, error))).unwrap();
            assert!(
                q.iterations <= 20,
                "reps {reps}: {} passes, errors {:?}",
                q.iterations,
                q.max_distance
            );
            // The rule itself: the run stops at the first third consecutive non-decrease.
            let mut previous = INITIAL_PREVIOUS_ERROR;
            let mut strikes = 0;
            let mut stop = None;
            for (pass, &e) in q.max_distance.iter().enumerate() {
                strikes = if e < previous { 0 } else { strikes + 1 };
                previous = e;
                if strikes == 3 || e == 0.0 {
                    stop = Some(pass + 1);
                    break;
                }
            }
            assert_eq!(stop, Some(q.iterations), "reps {reps}: errors {:?}", q.max_distance);
            assert_eq!(reported, q.max_distance.iter().copied().enumerate().collect::<Vec<_>>());
            assert_consistent(&vectors, 2, &q);
        }
    }

    #[test]
    fn empty_clusters_keep_their_value_and_are_counted() {
        // Stride 2 picks O[0] = 5 and O[2] = 5: the second is never strictly nearer than the
        // first, so its cluster stays empty and it must stay at 5.
        let vectors = [5.0, 0.0, 5.0, 10.0];
        let q = run(&vectors, 1, &VqSettings::new(2));
        assert_eq!(q.codebook, [5.0, 5.0]);
        assert_eq!(q.indices, [0, 0, 0, 0]);
        assert_eq!(q.unused, 1);
        assert_consistent(&vectors, 1, &q);
    }

    #[test]
    fn sixty_five_thousand_five_hundred_thirty_six_reps_fit_sixteen_bits() {
        // 65536 distinct values, each twice, shuffled: every index 0..=65535 must appear.
        let mut rng = Rng(42);
        let mut vectors: Vec<f32> = (0..2 * MAX_REPS).map(|i| (i % MAX_REPS) as f32).collect();
        for i in (1..vectors.len()).rev() {
            vectors.swap(i, (rng.next_u64() % (i as u64 + 1)) as usize);
        }
        let q = run(&vectors, 1, &VqSettings::new(MAX_REPS));
        assert_eq!((q.reps(), q.error(), q.unused), (MAX_REPS, 0.0, 0));
        assert_eq!(q.indices.iter().max(), Some(&u16::MAX));
        assert!(vectors
            .iter()
            .zip(&q.indices)
            .all(|(&v, &i)| q.codebook[usize::from(i)] == v));
    }

    #[test]
    fn bad_input_is_an_error_not_a_panic() {
        let v = [0.0f32; 8];
        let err =
            |vectors: &[f32], dim, settings: VqSettings| quantize(vectors, dim, &settings, |_, _| {}).unwrap_err();
        assert_eq!(err(&v, 2, VqSettings::new(0)), VqError::Reps(0));
        assert_eq!(err(&v, 2, VqSettings::new(MAX_REPS + 1)), VqError::Reps(MAX_REPS + 1));
        assert_eq!(err(&v, 0, VqSettings::new(4)), VqError::Dim);
        assert_eq!(err(&v, 3, VqSettings::new(4)), VqError::Length { len: 8, dim: 3 });
        assert_eq!(err(&[], 3, VqSettings::new(4)), VqError::Empty);
        assert_eq!(
            err(&[0.0, 1.0, f32::NAN, 0.0], 2, VqSettings::new(4)),
            VqError::NonFinite(1)
        );
        assert_eq!(
            err(
                &v,
                2,
                VqSettings {
                    max_iterations: 0,
                    ..VqSettings::new(4)
                }
            ),
            VqError::Setting("max_iterations")
        );
        assert_eq!(
            err(
                &v,
                2,
                VqSettings {
                    strikes: 0,
                    ..VqSettings::new(4)
                }
            ),
            VqError::Setting("strikes")
        );
    }

    #[test]
    fn fewer_vectors_than_reps_is_clamped() {
        let vectors = [0.0, 1.0, 2.0];
        let q = run(&vectors, 1, &VqSettings::new(10));
        assert_eq!((q.reps(), q.error()), (3, 0.0));
    }

    #[test]
    fn result_does_not_depend_on_the_thread_split() {
        let mut rng = Rng(7);
        let dim = 9;
        let vectors: Vec<f32> = (0..4001 * dim).map(|_| rng.signed()).collect();
        let settings = VqSettings::new(100);
        let threaded = run(&vectors, dim, &settings);
        // Reference: the same passes with every assignment on one thread.
        let mut codebook = strided_codebook(&vectors, dim, settings.reps);
        for _ in 0..threaded.iterations - 1 {
            let mut indices = vec![0; 4001];
            assign_range(&vectors, dim, &codebook, &mut indices, &mut vec![0.0; 4001]);
            update_means(&vectors, dim, &indices, &mut codebook);
        }
        let mut indices = vec![0; 4001];
        assign_range(&vectors, dim, &codebook, &mut indices, &mut vec![0.0; 4001]);
        assert_eq!((threaded.codebook, threaded.indices), (codebook, indices));
    }

    /// `cargo test --lib sh_lightmap::vq::tests::timing -- --ignored --nocapture`
    #[test]
    #[ignore = "timing report, not a check"]
    fn timing() {
        let mut rng = Rng(99);
        let dim = 16;
        let vectors: Vec<f32> = (0..20_000 * dim).map(|_| rng.signed()).collect();
        for reps in [1024, 4096] {
            let start = std::time::Instant::now();
            let q = run(&vectors, dim, &VqSettings::new(reps));
            let s = start.elapsed().as_secs_f64();
            println!(
                "S 20000 dim 16 reps {reps}: {s:.2} s, {} passes ({:.3} s/pass), error {:.4}, unused {}",
                q.iterations,
                s / q.iterations as f64,
                q.error(),
                q.unused
            );
        }
    }
}
