//! Tasks of unequal length on a few threads: longest first, each thread taking the next task
//! as it frees up (list scheduling), so that a long task does not start last and run alone
//! while the other threads idle. The results come back in the tasks' order whatever the
//! scheduling, so what a study writes does not depend on it.

use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// `work` applied to every task of `tasks` on the current rayon pool's threads, in decreasing
/// order of `cost` (ties in the tasks' order); the results in the tasks' order. `cost` is an
/// estimate for the order only (any unit, NaN last).
pub fn longest_first<T: Sync, R: Send>(
    tasks: &[T],
    cost: impl Fn(&T) -> f64,
    work: impl Fn(&T) -> R + Sync,
) -> Vec<R> {
    let cost: Vec<f64> = tasks
        .iter()
        .map(cost)
        .map(|c| if c.is_nan() { f64::NEG_INFINITY } else { c })
        .collect();
    let mut order: Vec<usize> = (0..tasks.len()).collect();
    order.sort_by(|&a, &b| cost[b].total_cmp(&cost[a]).then(a.cmp(&b)));
    let next = AtomicUsize::new(0);
    let slots: Vec<Mutex<Option<R>>> = tasks.iter().map(|_| Mutex::new(None)).collect();
    rayon::scope(|s| {
        for _ in 0..rayon::current_num_threads().min(tasks.len()) {
            s.spawn(|_| {
                while let Some(&j) = order.get(next.fetch_add(1, Ordering::Relaxed)) {
                    let result = work(&tasks[j]);
                    *slots[j].lock().unwrap_or_else(|e| e.into_inner()) = Some(result);
                }
            });
        }
    });
    slots
        .into_iter()
        .map(|m| {
            m.into_inner()
                .unwrap_or_else(|e| e.into_inner())
                .expect("every task ran")
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pool(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    /// On one thread the tasks run in decreasing cost, ties and NaN as stated; the results
    /// are in the tasks' order.
    #[test]
    fn one_thread_runs_the_longest_first_and_returns_in_order() {
        let costs = [2.0, f64::NAN, 5.0, 2.0, 9.0];
        let ran = Mutex::new(Vec::new());
        let results = pool(1).install(|| {
            longest_first(
                &[0usize, 1, 2, 3, 4],
                |&i| costs[i],
                |&i| {
                    ran.lock().unwrap().push(i);
                    10 * i
                },
            )
        });
        assert_eq!(ran.into_inner().unwrap(), vec![4, 2, 0, 3, 1]);
        assert_eq!(results, vec![0, 10, 20, 30, 40]);
    }

    /// On two threads the two longest tasks run at the same time (each waits, up to a
    /// minute, until the other has started: on one thread the first would wait in vain), and
    /// the results are in the tasks' order.
    #[test]
    fn two_threads_run_the_two_longest_together() {
        let millis = [1.0, 3.0, 2.0, 4.0];
        let started = AtomicUsize::new(0);
        let together = Mutex::new(Vec::new());
        let results = pool(2).install(|| {
            longest_first(
                &[0usize, 1, 2, 3],
                |&i| millis[i],
                |&i| {
                    if i == 3 || i == 1 {
                        started.fetch_add(1, Ordering::SeqCst);
                        let begun = std::time::Instant::now();
                        while started.load(Ordering::SeqCst) < 2
                            && begun.elapsed() < std::time::Duration::from_secs(60)
                        {
                            std::thread::yield_now();
                        }
                        let both = started.load(Ordering::SeqCst) >= 2;
                        together.lock().unwrap().push((i, both));
                    }
                    10 * i
                },
            )
        });
        let mut together = together.into_inner().unwrap();
        together.sort();
        assert_eq!(together, vec![(1, true), (3, true)]);
        assert_eq!(results, vec![0, 10, 20, 30]);
    }

    #[test]
    fn no_tasks_no_results() {
        let results: Vec<u8> = longest_first(&[] as &[u8], |_| 1.0, |&t| t);
        assert!(results.is_empty());
    }
}
