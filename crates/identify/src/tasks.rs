//! The task scheduler of one evaluation of a joint problem: every test's forward run is a
//! task, and its follow-up (the adjoint sweep or the forward sensitivities) another task
//! that becomes ready when the forward ends, so that with fewer cores than tests a
//! follow-up fills the core that another test's forward would leave idle.
//!
//! Three tests of equal cost on two cores take three task-times for forward + follow-up
//! this way (forwards first: `F1 F2 | F3 A1 | A2 A3`) instead of four with one phase after
//! the other (`F1 F2 | F3 - | A1 A2 | A3 -`). A follow-up may also be *speculative*
//! (computed ahead of a request that an optimizer usually makes next, e.g. the gradient
//! after the line search's cost): it then only runs on a core that would otherwise wait
//! for a forward still running, and only when it is expected (from the previous
//! evaluation's durations, with a 10% margin) to end before that forward does, so that it
//! should not delay the request that was made. It can when the estimates are wrong: the
//! evaluation returns when every task it started has ended, a speculative one included.
//!
//! Which task runs where and when depends on timing; what each task computes does not (it
//! owns its test's workspace and cache entry, and the caller combines the results in test
//! order), so results are bit-identical for any number of threads and any timing.

use std::collections::VecDeque;
use std::sync::Mutex;
use std::time::Instant;

/// The follow-up of one test's forward run in one evaluation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Follow {
    /// No follow-up.
    None,
    /// Asked for: runs as soon as the forward (if any) is done.
    Needed,
    /// May be computed ahead on an otherwise idle core; skipped otherwise.
    Speculative,
}

/// The work of one test in one evaluation.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Todo {
    /// Run the forward first (otherwise the follow-up, if any, is ready at once).
    pub forward: bool,
    /// The follow-up.
    pub follow: Follow,
    /// Expected seconds of the forward and of the follow-up (from the previous
    /// evaluation; `None`: unknown, and a speculative follow-up is then skipped).
    pub expected: (Option<f64>, Option<f64>),
}

/// What the scheduler measured of one test.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Done {
    /// Seconds of the forward, when it ran.
    pub forward: Option<f64>,
    /// Seconds of the follow-up, when it ran.
    pub follow: Option<f64>,
}

#[derive(Clone, Copy, Debug)]
enum Task {
    Forward(usize),
    Follow(usize),
}

struct Queue {
    forwards: VecDeque<usize>,
    needed: VecDeque<usize>,
    speculative: VecDeque<usize>,
    /// Forwards running: test and start (seconds since the evaluation began).
    running: Vec<(usize, f64)>,
    done: Vec<Done>,
}

struct Shared<'a, S, F, G> {
    clock: Instant,
    todo: &'a [Todo],
    queue: Mutex<Queue>,
    slots: Vec<Mutex<&'a mut S>>,
    forward: F,
    follow: G,
}

impl Queue {
    /// The next task: forwards first (they are on the critical path), then the follow-ups
    /// asked for, then a speculative one if it fits in the idle time.
    fn pick(&mut self, now: f64, todo: &[Todo]) -> Option<Task> {
        if let Some(k) = self.forwards.pop_front() {
            self.running.push((k, now));
            return Some(Task::Forward(k));
        }
        if let Some(k) = self.needed.pop_front() {
            return Some(Task::Follow(k));
        }
        let k = self.speculative.pop_front()?;
        // the latest expected end of a forward still running
        let horizon = self
            .running
            .iter()
            .filter_map(|&(j, start)| todo[j].expected.0.map(|e| start + e))
            .fold(None, |m: Option<f64>, e| Some(m.map_or(e, |m| m.max(e))));
        match (horizon, todo[k].expected.1) {
            // a tenth of margin for the noise of the estimates: it must be expected to end
            // before the forward does, with room to spare
            (Some(h), Some(e)) if now + 1.1 * e <= h => Some(Task::Follow(k)),
            _ => None,
        }
    }
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    // a panic in a task poisons nothing we cannot use: the panic itself propagates
    m.lock().unwrap_or_else(|e| e.into_inner())
}

fn job<'s, 'a: 's, S, F, G>(scope: &rayon::Scope<'s>, sh: &'s Shared<'a, S, F, G>)
where
    S: Send,
    F: Fn(usize, &mut S) -> bool + Sync,
    G: Fn(usize, &mut S) + Sync,
{
    let now = sh.clock.elapsed().as_secs_f64();
    let Some(task) = lock(&sh.queue).pick(now, sh.todo) else {
        return;
    };
    match task {
        Task::Forward(k) => {
            let ok = (sh.forward)(k, &mut lock(&sh.slots[k]));
            let end = sh.clock.elapsed().as_secs_f64();
            let mut q = lock(&sh.queue);
            q.running.retain(|&(j, _)| j != k);
            q.done[k].forward = Some(end - now);
            if ok {
                let follow = match sh.todo[k].follow {
                    Follow::None => false,
                    Follow::Needed => {
                        q.needed.push_back(k);
                        true
                    }
                    Follow::Speculative => {
                        q.speculative.push_back(k);
                        true
                    }
                };
                drop(q);
                if follow {
                    scope.spawn(move |s| job(s, sh));
                }
            }
        }
        Task::Follow(k) => {
            (sh.follow)(k, &mut lock(&sh.slots[k]));
            let end = sh.clock.elapsed().as_secs_f64();
            lock(&sh.queue).done[k].follow = Some(end - now);
        }
    }
}

/// Runs every test's [`Todo`] on `pool` (or the current rayon pool): `forward(k, slot)`
/// returns whether test `k`'s follow-up may run (false after a failed forward);
/// `follow(k, slot)` is the follow-up. Each slot is touched by one task at a time.
/// Returns what ran and how long it took, per test.
pub(crate) fn run<S, F, G>(
    pool: Option<&rayon::ThreadPool>,
    slots: &mut [S],
    todo: &[Todo],
    forward: F,
    follow: G,
) -> Vec<Done>
where
    S: Send,
    F: Fn(usize, &mut S) -> bool + Sync + Send,
    G: Fn(usize, &mut S) + Sync + Send,
{
    let n = slots.len();
    let mut queue = Queue {
        forwards: VecDeque::new(),
        needed: VecDeque::new(),
        speculative: VecDeque::new(),
        running: Vec::new(),
        done: vec![Done::default(); n],
    };
    for (k, t) in todo.iter().enumerate() {
        if t.forward {
            queue.forwards.push_back(k);
        } else {
            match t.follow {
                Follow::None => {}
                Follow::Needed => queue.needed.push_back(k),
                // nothing runs to hide it behind
                Follow::Speculative => {}
            }
        }
    }
    let tasks = queue.forwards.len() + queue.needed.len();
    // one test, or one thread: in order on this thread (no speculation: nothing is idle)
    let threads = pool.map_or_else(rayon::current_num_threads, |p| p.current_num_threads());
    if tasks <= 1 || threads == 1 {
        // inside the pool all the same (the global one without a pool of the problem's
        // own): the tasks' own parallel passes (the Gauss-point loops, the parameters of
        // the sensitivities) then run on the pool's workers with its threads
        let mut serial = || {
            let mut done = vec![Done::default(); n];
            for (k, (slot, t)) in slots.iter_mut().zip(todo).enumerate() {
                let clock = Instant::now();
                let ok = if t.forward {
                    let ok = forward(k, slot);
                    done[k].forward = Some(clock.elapsed().as_secs_f64());
                    ok
                } else {
                    true
                };
                if ok && t.follow == Follow::Needed {
                    let clock = Instant::now();
                    follow(k, slot);
                    done[k].follow = Some(clock.elapsed().as_secs_f64());
                }
            }
            done
        };
        return match pool {
            Some(p) => p.install(serial),
            None => rayon::scope(|_| serial()),
        };
    }
    let shared = Shared {
        clock: Instant::now(),
        todo,
        queue: Mutex::new(queue),
        slots: slots.iter_mut().map(Mutex::new).collect(),
        forward,
        follow,
    };
    let all = || {
        rayon::scope(|s| {
            for _ in 0..tasks {
                s.spawn(|s| job(s, &shared));
            }
        })
    };
    match pool {
        Some(p) => p.install(all),
        None => all(),
    }
    let q = shared.queue.into_inner().unwrap_or_else(|e| e.into_inner());
    q.done
}

#[cfg(test)]
mod tests {
    use super::*;

    fn todo(n: usize, forward: bool, follow: Follow) -> Vec<Todo> {
        vec![
            Todo {
                forward,
                follow,
                expected: (Some(1.0), Some(1.0)),
            };
            n
        ]
    }

    /// Every forward runs once; every needed follow-up once, after its forward, and never
    /// after a failed forward.
    #[test]
    fn needed_follow_ups_run_once_after_their_forward() {
        for threads in [1, 2, 3] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut slots: Vec<Vec<&str>> = vec![Vec::new(); 5];
            let done = run(
                Some(&pool),
                &mut slots,
                &todo(5, true, Follow::Needed),
                |k, s: &mut Vec<&str>| {
                    s.push("forward");
                    k != 3
                },
                |_, s| s.push("follow"),
            );
            for (k, s) in slots.iter().enumerate() {
                let want: &[&str] = if k == 3 {
                    &["forward"]
                } else {
                    &["forward", "follow"]
                };
                assert_eq!(s, want, "test {k} on {threads} threads");
                assert!(done[k].forward.is_some());
                assert_eq!(done[k].follow.is_some(), k != 3);
            }
        }
    }

    /// The serial path (one task, or one thread) runs inside the given pool too, so that
    /// the tasks' own parallel passes use its threads, not the caller's; without a pool,
    /// on a worker of the global pool.
    #[test]
    fn serial_runs_use_the_pool_they_are_given() {
        for (threads, tests) in [(1, 3), (3, 1)] {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            let mut seen = vec![(0_usize, 0_usize); tests];
            run(
                Some(&pool),
                &mut seen,
                &todo(tests, true, Follow::Needed),
                |_, s: &mut (usize, usize)| {
                    s.0 = rayon::current_num_threads();
                    true
                },
                |_, s| s.1 = rayon::current_num_threads(),
            );
            assert_eq!(seen, vec![(threads, threads); tests], "{threads} threads");
        }
        // without a pool: on a worker of the global pool, whatever thread called
        let mut on_worker = vec![false; 1];
        run(
            None,
            &mut on_worker,
            &todo(1, true, Follow::None),
            |_, s: &mut bool| {
                *s = rayon::current_thread_index().is_some();
                true
            },
            |_, _| {},
        );
        assert_eq!(on_worker, [true]);
    }

    /// Follow-ups without a forward run at once; speculative ones never run when nothing
    /// is running to hide them behind, nor on one thread.
    #[test]
    fn speculative_follow_ups_need_idle_time() {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(2)
            .build()
            .unwrap();
        let mut slots = vec![0_u32; 3];
        run(
            Some(&pool),
            &mut slots,
            &todo(3, false, Follow::Needed),
            |_, _| unreachable!("no forward asked for"),
            |_, s: &mut u32| *s += 1,
        );
        assert_eq!(slots, [1, 1, 1]);
        // one test: its forward ends before anything could hide its follow-up
        let mut one = vec![0_u32];
        let done = run(
            Some(&pool),
            &mut one,
            &todo(1, true, Follow::Speculative),
            |_, _| true,
            |_, s: &mut u32| *s += 1,
        );
        assert_eq!(one, [0]);
        assert!(done[0].follow.is_none());
        // unknown durations: never speculated
        let mut slots = vec![0_u32; 3];
        let mut t = todo(3, true, Follow::Speculative);
        t.iter_mut().for_each(|t| t.expected = (None, None));
        run(
            Some(&pool),
            &mut slots,
            &t,
            |_, _| {
                std::thread::sleep(std::time::Duration::from_millis(5));
                true
            },
            |_, s: &mut u32| *s += 1,
        );
        assert_eq!(slots, [0, 0, 0]);
    }

    /// The schedule's decision rule: forwards first, then needed, then a speculative
    /// follow-up only if it ends (expected) by the last running forward's expected end.
    #[test]
    fn the_queue_picks_forwards_then_needed_then_what_fits() {
        let todo = vec![
            Todo {
                forward: true,
                follow: Follow::Speculative,
                expected: (Some(1.0), Some(0.5)),
            },
            Todo {
                forward: true,
                follow: Follow::Speculative,
                expected: (Some(1.0), Some(2.0)),
            },
            Todo {
                forward: true,
                follow: Follow::Needed,
                expected: (Some(1.0), Some(1.0)),
            },
        ];
        let mut q = Queue {
            forwards: VecDeque::from([2]),
            needed: VecDeque::from([0]),
            speculative: VecDeque::from([0, 1]),
            running: vec![],
            done: vec![Done::default(); 3],
        };
        assert!(matches!(q.pick(0.0, &todo), Some(Task::Forward(2))));
        assert!(matches!(q.pick(0.0, &todo), Some(Task::Follow(0))));
        // test 2's forward runs until 1.0 (expected): 0's 0.5 s fits at 0.2, 1's 2 s does not
        assert!(matches!(q.pick(0.2, &todo), Some(Task::Follow(0))));
        assert!(q.pick(0.2, &todo).is_none());
        assert!(q.speculative.is_empty());
        // nothing running: no speculation
        q.running.clear();
        q.speculative.push_back(0);
        assert!(q.pick(0.0, &todo).is_none());
    }
}
