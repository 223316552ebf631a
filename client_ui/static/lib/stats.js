// Pure summary statistics of measurements (response times): mean, percentiles, quartiles and their range.

/** Finite numbers only. */
function finite(values) {
  return values.map(Number).filter(Number.isFinite);
}

/** Arithmetic mean; NaN for no values. */
export function mean(values) {
  const numbers = finite(values);
  return numbers.length ? numbers.reduce((sum, v) => sum + v, 0) / numbers.length : NaN;
}

/** Nearest-rank percentile (p in 0..100); NaN for no values. */
export function percentile(values, p) {
  const numbers = finite(values).sort((a, b) => a - b);
  if (!numbers.length) return NaN;
  const rank = Math.ceil((Math.min(100, Math.max(0, p)) / 100) * numbers.length);
  return numbers[Math.max(0, rank - 1)];
}

/** {count, last, mean, p95} of the last `n` values. */
export function summarize(values, n = 50) {
  const window = finite(values).slice(-n);
  return { count: window.length, last: window.length ? window[window.length - 1] : NaN, mean: mean(window),
    p95: percentile(window, 95) };
}

/** The p-quantile (0..1) of ascending numbers, interpolated linearly between ranks (numpy's default,
 *  Python's statistics.quantiles(method="inclusive")); NaN for none. */
export function quantile(sorted, p) {
  if (!sorted.length) return NaN;
  const position = (sorted.length - 1) * Math.min(1, Math.max(0, p));
  const below = Math.floor(position);
  const above = Math.min(sorted.length - 1, below + 1);
  return sorted[below] + (sorted[above] - sorted[below]) * (position - below);
}

/** {count, min, max, mean, q1, q3, jitter} of round trips in ms; NaN figures for none. */
export function legFigures(values) {
  const sorted = finite(values).sort((a, b) => a - b);
  const count = sorted.length;
  const q1 = quantile(sorted, 0.25);
  const q3 = quantile(sorted, 0.75);
  return {
    count,
    min: count ? sorted[0] : NaN,
    max: count ? sorted[count - 1] : NaN,
    mean: count ? sorted.reduce((sum, value) => sum + value, 0) / count : NaN,
    q1, q3, jitter: q3 - q1,
  };
}
