//! The output rows of a run: the probes read at the increments that fall on the output
//! times (or interpolated between increments that do not), and the impacts noted on the way.

/// Turns the rows of increments into output rows: on increments that fall on the output times,
/// row for row; otherwise (a stability study's increment) by quadratic interpolation through
/// the last three increments around each output time (error O(h³) on the accurate modes).
pub(super) struct RowSampler {
    pub(super) times: Vec<f64>,
    next: usize,
    /// Whether the increment divides the output interval (rows fall on increments).
    pub(super) on_steps: bool,
    /// The last (up to) three rows of increments.
    window: std::collections::VecDeque<Vec<f64>>,
    /// Time round-off allowance.
    slack: f64,
}

impl RowSampler {
    pub(super) fn new(times: &[f64], interval: f64, h: f64) -> Self {
        let per = interval / h;
        RowSampler {
            times: times.to_vec(),
            next: 0,
            on_steps: (per - per.round()).abs() <= 1e-9 * per.max(1.0),
            window: std::collections::VecDeque::with_capacity(3),
            slack: 1e-9 * h,
        }
    }

    /// Take the row of the latest increment (time in column 0); write the output rows it
    /// completes.
    pub(super) fn push(&mut self, row: Vec<f64>, rows: &mut Vec<Vec<f64>>) {
        if self.on_steps {
            rows.push(row);
            return;
        }
        if self.window.len() == 3 {
            self.window.pop_front();
        }
        self.window.push_back(row);
        let latest = self.window.back().map_or(0.0, |r| r[0]);
        while self.next < self.times.len() && self.times[self.next] <= latest + self.slack {
            let t = self.times[self.next];
            let points: Vec<&Vec<f64>> = self.window.iter().collect();
            let weights: Vec<f64> = (0..points.len())
                .map(|i| {
                    (0..points.len())
                        .filter(|&j| j != i)
                        .map(|j| (t - points[j][0]) / (points[i][0] - points[j][0]))
                        .product()
                })
                .collect();
            let mut out: Vec<f64> = (0..points[0].len())
                .map(|c| points.iter().zip(&weights).map(|(p, w)| w * p[c]).sum())
                .collect();
            out[0] = t;
            rows.push(out);
            self.next += 1;
        }
    }
}

/// Note which contact pairs press at increment `n`, time n·`h` (normal forces `contact`) in
/// `pressed`, and an impact where one that did not press at the last increment noted starts
/// to (the time is formed only then).
///
/// The increment loops call this at every increment, and an impact is rare: the test is
/// inlined and the noting ([`note_start`]) is a cold call, so that the loop neither forms
/// the time nor keeps its registers on the stack around a call it seldom makes.
#[inline(always)]
pub(super) fn note_impacts(
    pressed: &mut [Option<bool>],
    contact: &[f64],
    (n, h): (u64, f64),
    impacts: &mut Vec<f64>,
) {
    for (was, force) in pressed.iter_mut().zip(contact) {
        let now = *force > 0.0;
        if now && *was == Some(false) {
            note_start((n, h), impacts);
        }
        *was = Some(now);
    }
}

/// An impact [`note_impacts`] found: a pair starts to press at increment `n`, time n·`h`.
#[cold]
#[inline(never)]
fn note_start((n, h): (u64, f64), impacts: &mut Vec<f64>) {
    impacts.push(n as f64 * h);
}
