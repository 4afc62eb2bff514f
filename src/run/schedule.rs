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

    /// On two threads the two longest tasks start first (each thread then sleeps at least
    /// 20 ms before it takes another), and the results are in the tasks' order.
    #[test]
    fn two_threads_start_with_the_two_longest() {
        let millis = [20u64, 30, 30, 40];
        let started = Mutex::new(Vec::new());
        let results = pool(2).install(|| {
            longest_first(
                &[0usize, 1, 2, 3],
                |&i| millis[i] as f64,
                |&i| {
                    started.lock().unwrap().push(i);
                    std::thread::sleep(std::time::Duration::from_millis(millis[i]));
                    millis[i]
                },
            )
        });
        let started = started.into_inner().unwrap();
        let mut first_two = started[..2].to_vec();
        first_two.sort();
        assert_eq!(first_two, vec![1, 3], "started: {started:?}");
        assert_eq!(results, vec![20, 30, 30, 40]);
    }

    #[test]
    fn no_tasks_no_results() {
        let results: Vec<u8> = longest_first(&[] as &[u8], |_| 1.0, |&t| t);
        assert!(results.is_empty());
    }
}
