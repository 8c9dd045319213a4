//! Data-parallel helpers on scoped threads for the CPU side of bakes and builds: a map that keeps
//! its input's order, and a fold over contiguous ranges whose pieces are joined in order (so the
//! same pieces always join to the same answer). Where the system gives no thread, the calling
//! thread does that share of the work.

use bytemuck::Zeroable;
use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

/// The cores this process may use (1 where the system does not say).
pub fn cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `work` over `0..len` in up to `threads` contiguous pieces of at least `min_piece` (one piece,
/// on this thread and at no cost over calling `work`, when `len` is below twice that), all but
/// the first on threads of their own; the results are joined with `join` in order of their
/// pieces.
pub fn fold_ranges<T: Send>(
    len: usize,
    threads: usize,
    min_piece: usize,
    work: impl Fn(Range<usize>) -> T + Sync,
    join: impl Fn(T, T) -> T,
) -> T {
    let pieces = (len / min_piece.max(1)).clamp(1, threads.max(1));
    if pieces == 1 {
        return work(0..len);
    }
    let step = len.div_ceil(pieces);
    let range = |k: usize| k * step..((k + 1) * step).min(len);
    std::thread::scope(|scope| {
        let work = &work;
        let others: Vec<_> = (1..pieces)
            .map(|k| {
                (
                    k,
                    std::thread::Builder::new().spawn_scoped(scope, move || work(range(k))),
                )
            })
            .collect();
        let mut out = work(range(0));
        for (k, handle) in others {
            // A panic in the thread is a bug in the work; carry it to the caller.
            let piece = match handle {
                Ok(h) => h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)),
                Err(_) => work(range(k)),
            };
            out = join(out, piece);
        }
        out
    })
}

/// `f` of every item, in order, in pieces of `piece` items taken by as many threads as there are
/// cores (each takes the next piece when done, so uneven pieces balance).
pub fn map<T: Sync, U: Zeroable + Send>(items: &[T], piece: usize, f: impl Fn(&T) -> U + Sync) -> Vec<U> {
    let mut out: Vec<U> = (0..items.len()).map(|_| U::zeroed()).collect();
    let piece = piece.max(1);
    let pieces: Vec<Mutex<(&[T], &mut [U])>> = items.chunks(piece).zip(out.chunks_mut(piece)).map(Mutex::new).collect();
    let next = AtomicUsize::new(0);
    let work = || {
        while let Some(piece) = pieces.get(next.fetch_add(1, Ordering::Relaxed)) {
            let mut piece = piece.lock().unwrap_or_else(|e| e.into_inner());
            let (src, dst) = &mut *piece;
            for (s, d) in src.iter().zip(dst.iter_mut()) {
                *d = f(s);
            }
        }
    };
    let threads = cores().min(pieces.len());
    std::thread::scope(|scope| {
        for _ in 1..threads {
            if std::thread::Builder::new().spawn_scoped(scope, work).is_err() {
                break;
            }
        }
        work();
    });
    drop(pieces);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every item lands at its own index, across many pieces and threads (including a last
    /// piece shorter than the others, and no items at all).
    #[test]
    fn map_keeps_every_item_in_place() {
        for n in [0usize, 1, 999, 100_003] {
            let items: Vec<u64> = (0..n as u64).collect();
            let out: Vec<u64> = map(&items, 1000, |&x| x * x + 7);
            assert_eq!(out.len(), n);
            assert!(
                out.iter().enumerate().all(|(i, &y)| y == (i as u64) * (i as u64) + 7),
                "n = {n}"
            );
        }
    }

    /// The pieces cover `0..len` once, contiguously, and are joined in their order; a short
    /// input is one piece.
    #[test]
    fn fold_ranges_joins_contiguous_pieces_in_order() {
        let collect = |len: usize, threads: usize, min_piece: usize| {
            fold_ranges(
                len,
                threads,
                min_piece,
                |r| vec![r],
                |mut a, b| {
                    a.extend(b);
                    a
                },
            )
        };
        let pieces = collect(10_007, 4, 1000);
        assert_eq!(pieces.len(), 4);
        assert_eq!(pieces.first().map(|r| r.start), Some(0));
        assert_eq!(pieces.last().map(|r| r.end), Some(10_007));
        assert!(pieces.windows(2).all(|w| w[0].end == w[1].start), "{pieces:?}");
        assert_eq!(collect(1_999, 8, 1000), vec![0..1_999]);
        assert_eq!(collect(0, 8, 1000), vec![0..0]);
    }
}
