// SPDX-License-Identifier: Apache-2.0
// tacse3-truth: clock offset from a controller-side candump log, or by cross-correlating the
// angular speed of the recording's pipeline estimate with the robot log's.
#include "tacse3/tools/truth/clock_sync.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numeric>
#include <variant>

#include "tacse3/fileio/file_io.hpp"
#include "tacse3/protocol/protocol.hpp"

namespace tacse3::tools::truth {

namespace proto = tacse3::protocol;

namespace {

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t m = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m), v.end());
  const double hi = v[m];
  if (v.size() % 2 == 1) return hi;
  return 0.5 * (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(m)));
}

double robust_sigma(const std::vector<double>& v) {
  const double m = median(v);
  std::vector<double> d(v.size());
  for (std::size_t i = 0; i < v.size(); ++i) d[i] = std::abs(v[i] - m);
  return 1.4826 * median(std::move(d));
}

std::string read_text(const std::filesystem::path& file, std::size_t limit, std::string* text) {
  const fileio::ReadResult r = fileio::read_regular_file(file, limit, text);
  if (r.ok()) return {};
  switch (r.error) {
    case fileio::ReadError::kNotFound:
      return file.string() + ": no such file";
    case fileio::ReadError::kNotRegular:
      return file.string() + ": is " + r.kind + ", not a regular file";
    case fileio::ReadError::kTooLarge:
      return file.string() + ": larger than " + fileio::size_text(limit);
    default:
      return file.string() + ": cannot read" + fileio::os_error(r.os_errno);
  }
}

}  // namespace

std::string sync_by_can_log(std::string_view text, const std::string& name, std::int64_t first_ns,
                            std::int64_t last_ns, CanSync* out) {
  proto::CycleReassembler cycles;
  const proto::IdLayout layout{};
  std::vector<double> lag_s, latency_s;  // arrival - sample; reported latency p50
  // Arrival of each counter value's Timestamp frame: the cycle's first frame on the bus.
  std::array<std::uint64_t, 16> stamp_arrival_us{};
  std::size_t line_no = 0, outside = 0;
  while (!text.empty()) {
    const std::size_t nl = text.find('\n');
    std::string_view line = text.substr(0, nl);
    text.remove_prefix(nl == std::string_view::npos ? text.size() : nl + 1);
    ++line_no;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) continue;
    proto::LogRecord rec;
    if (proto::parse_candump_line(line, rec) != proto::Status::kOk) {
      return name + " line " + std::to_string(line_no) +
             ": not a candump -L line (\"(seconds.micros) iface id#data\")";
    }
    if (rec.error_frame || rec.rtr) continue;
    proto::Decoded d;
    if (proto::decode(rec.frame, layout, d) != proto::Status::kOk) continue;
    if (const auto* timing = std::get_if<proto::TimingMsg>(&d.payload);
        timing != nullptr && d.node_id == cycles.endpoint().node_id &&
        std::isfinite(timing->latency_p50_s)) {
      latency_s.push_back(timing->latency_p50_s);
    }
    if (std::holds_alternative<proto::TimestampMsg>(d.payload) &&
        d.node_id == cycles.endpoint().node_id) {
      stamp_arrival_us[std::get<proto::TimestampMsg>(d.payload).counter & 0x0F] = rec.time_us;
    }
    proto::Cycle c;
    if (cycles.feed(d, c) != proto::CycleReassembler::Result::kComplete) continue;
    const std::int64_t sample_ns = static_cast<std::int64_t>(c.timestamp_us) * 1000;
    if (sample_ns < first_ns - 1000 || sample_ns > last_ns) {
      ++outside;
      continue;
    }
    const std::uint64_t arrival_us = stamp_arrival_us[c.counter & 0x0F];
    lag_s.push_back((static_cast<double>(arrival_us) - static_cast<double>(c.timestamp_us)) * 1e-6);
  }
  if (lag_s.empty()) {
    return name + ": no complete tacse3 cycle (node 1, 11-bit identifiers) whose SampleTime " +
           "falls within the recording (" + std::to_string(outside) +
           " outside it): is this the controller's candump -L log of this recording?";
  }
  CanSync s;
  s.cycles = lag_s.size();
  s.latency_reports = latency_s.size();
  s.latency_s = median(latency_s);
  s.spread_s = robust_sigma(lag_s);
  // Subtracting in µs keeps the precision of epoch stamps (1.7e9 s).
  s.offset_ns = std::llround((median(lag_s) - s.latency_s) * 1e9);
  *out = s;
  return {};
}

std::string read_can_sync(const std::filesystem::path& file, std::int64_t first_ns,
                          std::int64_t last_ns, CanSync* out) {
  std::string text;
  if (std::string e = read_text(file, kMaxCanLogBytes, &text); !e.empty()) return e;
  return sync_by_can_log(text, file.string(), first_ns, last_ns, out);
}

std::vector<double> interval_speed(const std::vector<std::int64_t>& t_ns,
                                   const std::vector<Eigen::Quaterniond>& q) {
  std::vector<double> s(t_ns.size(), 0.0);
  for (std::size_t i = 1; i < t_ns.size(); ++i) {
    s[i] = rotation_angle(q[i - 1].conjugate() * q[i]) /
           (static_cast<double>(t_ns[i] - t_ns[i - 1]) * 1e-9);
  }
  return s;
}

double difference_noise(const std::vector<double>& s) {
  if (s.size() < 3) return 0.0;
  std::vector<double> d(s.size() - 1);
  for (std::size_t i = 0; i + 1 < s.size(); ++i) d[i] = s[i + 1] - s[i];
  return robust_sigma(d) / std::sqrt(2.0);
}

namespace {

// Pearson correlation of a and b from element `first` on (0 when either is constant).
double pearson(const std::vector<double>& a, const std::vector<double>& b, std::size_t first) {
  const double n = static_cast<double>(a.size() - first);
  const auto skip = static_cast<std::ptrdiff_t>(first);
  const double ma = std::accumulate(a.begin() + skip, a.end(), 0.0) / n;
  const double mb = std::accumulate(b.begin() + skip, b.end(), 0.0) / n;
  double sab = 0.0, saa = 0.0, sbb = 0.0;
  for (std::size_t i = first; i < a.size(); ++i) {
    sab += (a[i] - ma) * (b[i] - mb);
    saa += (a[i] - ma) * (a[i] - ma);
    sbb += (b[i] - mb) * (b[i] - mb);
  }
  return saa > 0.0 && sbb > 0.0 ? sab / std::sqrt(saa * sbb) : 0.0;
}

// The log's angular speed over the recording's frame intervals, read at t + offset
// (element 0 unused, as in interval_speed).
std::vector<double> log_speed(const std::vector<std::int64_t>& t_ns, const PoseLog& log,
                              double offset_ns) {
  std::vector<double> s(t_ns.size(), 0.0);
  const std::int64_t off = std::llround(offset_ns);
  Eigen::Quaterniond prev = log.at(t_ns[0] + off).q;
  for (std::size_t i = 1; i < t_ns.size(); ++i) {
    const Eigen::Quaterniond q = log.at(t_ns[i] + off).q;
    s[i] =
        rotation_angle(prev.conjugate() * q) / (static_cast<double>(t_ns[i] - t_ns[i - 1]) * 1e-9);
    prev = q;
  }
  return s;
}

// Linear interpolation of the series (t, v) at time x (clamped at the ends).
double sample(const std::vector<std::int64_t>& t, const std::vector<double>& v, double x) {
  if (x <= static_cast<double>(t.front())) return v.front();
  if (x >= static_cast<double>(t.back())) return v.back();
  const auto it = std::upper_bound(
      t.begin(), t.end(), x, [](double a, std::int64_t b) { return a < static_cast<double>(b); });
  const std::size_t b = static_cast<std::size_t>(it - t.begin()), a = b - 1;
  const double u = (x - static_cast<double>(t[a])) / static_cast<double>(t[b] - t[a]);
  return (1.0 - u) * v[a] + u * v[b];
}

double range(const std::vector<double>& v) {
  const auto [lo, hi] = std::minmax_element(v.begin(), v.end());
  return *hi - *lo;
}

double snr(const std::vector<double>& v) {
  const double noise = difference_noise(v), r = range(v);
  if (noise > 0.0) return r / noise;
  return r > 0.0 ? 1e9 : 0.0;
}

// Correlation of r (uniform grid) with every window of g (same grid) at integer lags.
std::vector<double> grid_correlation(const std::vector<double>& r, const std::vector<double>& g) {
  const std::size_t n = r.size(), lags = g.size() - n + 1;
  const double dn = static_cast<double>(n);
  const double mr = std::accumulate(r.begin(), r.end(), 0.0) / dn;
  std::vector<double> rc(n);
  double srr = 0.0;
  for (std::size_t i = 0; i < n; ++i) srr += (rc[i] = r[i] - mr) * rc[i];
  std::vector<double> s1(g.size() + 1, 0.0), s2(g.size() + 1, 0.0);
  for (std::size_t j = 0; j < g.size(); ++j) {
    s1[j + 1] = s1[j] + g[j];
    s2[j + 1] = s2[j] + g[j] * g[j];
  }
  std::vector<double> c(lags, 0.0);
  for (std::size_t k = 0; k < lags; ++k) {
    double sab = 0.0;  // sum rc_i g_{i+k} = sum rc_i (g_{i+k} - mean), since sum rc_i = 0
    for (std::size_t i = 0; i < n; ++i) sab += rc[i] * g[i + k];
    const double sum = s1[k + n] - s1[k];
    const double sgg = (s2[k + n] - s2[k]) - sum * sum / dn;
    c[k] = srr > 0.0 && sgg > 1e-12 * dn ? sab / std::sqrt(srr * sgg) : 0.0;
  }
  return c;
}

}  // namespace

namespace {

// The median frame period: the coarse grid's step.
std::int64_t frame_period(const std::vector<std::int64_t>& t_ns) {
  std::vector<std::int64_t> dt(t_ns.size() - 1);
  for (std::size_t i = 0; i + 1 < t_ns.size(); ++i) dt[i] = t_ns[i + 1] - t_ns[i];
  std::nth_element(dt.begin(), dt.begin() + static_cast<std::ptrdiff_t>(dt.size() / 2), dt.end());
  return dt[dt.size() / 2];
}

// Both speeds on a grid of one frame period, each sample at the middle of its interval: the
// recording's from its first interval (r), the log's from its first sample (g). Grid lag k puts
// r[0] on g[k]; `grid0` is the clock offset of lag 0.
struct SpeedGrids {
  std::vector<double> r, g;
  double grid0 = 0.0;
};

SpeedGrids speed_grids(const std::vector<std::int64_t>& t_ns, const std::vector<double>& speed,
                       const PoseLog& log, std::int64_t step) {
  const std::size_t n = t_ns.size();
  std::vector<std::int64_t> mid(n - 1);
  std::vector<double> rec_speed(n - 1);
  for (std::size_t i = 1; i < n; ++i) {
    mid[i - 1] = t_ns[i - 1] + (t_ns[i] - t_ns[i - 1]) / 2;
    rec_speed[i - 1] = speed[i];
  }
  const double h = static_cast<double>(step);
  SpeedGrids out;
  out.r.resize(static_cast<std::size_t>((mid.back() - mid.front()) / step) + 1);
  for (std::size_t i = 0; i < out.r.size(); ++i) {
    out.r[i] =
        sample(mid, rec_speed, static_cast<double>(mid.front()) + static_cast<double>(i) * h);
  }
  out.g.resize(static_cast<std::size_t>((log.t_ns.back() - log.t_ns.front()) / step));
  for (std::size_t j = 0; j < out.g.size(); ++j) {
    const std::int64_t tau = log.t_ns.front() + static_cast<std::int64_t>(j) * step;
    out.g[j] = rotation_angle(log.at(tau).q.conjugate() * log.at(tau + step).q) / (1e-9 * h);
  }
  out.grid0 = static_cast<double>(log.t_ns.front() + step / 2) - static_cast<double>(mid.front());
  return out;
}

// The best correlation outside the main lobe (the lags around `best` where the correlation stays
// above half of it), and its lag; -1 when every lag is in the lobe.
std::pair<double, std::size_t> runner_up(const std::vector<double>& c, std::size_t best) {
  std::size_t lo = best, hi = best;
  while (lo > 0 && c[lo - 1] >= 0.5 * c[best]) --lo;
  while (hi + 1 < c.size() && c[hi + 1] >= 0.5 * c[best]) ++hi;
  std::pair<double, std::size_t> r{-1.0, 0};
  for (std::size_t k = 0; k < c.size(); ++k) {
    if ((k < lo || k > hi) && c[k] > r.first) r = {c[k], k};
  }
  return r;
}

// Golden-section search for the maximum of f on [x0, x3], to 1 µs.
template <class F>
double golden_max(F f, double x0, double x3) {
  const double phi = 0.5 * (std::sqrt(5.0) - 1.0);
  double x1 = x3 - phi * (x3 - x0), x2 = x0 + phi * (x3 - x0);
  double f1 = f(x1), f2 = f(x2);
  while (x3 - x0 > 1e3) {
    if (f1 > f2) {
      x3 = x2, x2 = x1, f2 = f1;
      x1 = x3 - phi * (x3 - x0), f1 = f(x1);
    } else {
      x0 = x1, x1 = x2, f1 = f2;
      x2 = x0 + phi * (x3 - x0), f2 = f(x2);
    }
  }
  return 0.5 * (x0 + x3);
}

std::string too_little_motion(const SpeedGrids& grids, const PoseLog& log) {
  char buf[320];
  if (const double s = snr(grids.r); s < kMinMotionSnr) {
    std::snprintf(buf, sizeof(buf),
                  "--clock-offset auto: too little rotation in the recording to sync on (the "
                  "pipeline's angular speed spans %.1f times its noise, at least %.0f needed); "
                  "give --can-log or --clock-offset SECONDS",
                  s, kMinMotionSnr);
    return buf;
  }
  if (const double s = snr(grids.g); s < kMinMotionSnr) {
    std::snprintf(buf, sizeof(buf),
                  ": too little rotation to sync on (its angular speed spans %.1f times its "
                  "noise, at least %.0f needed); give --can-log or --clock-offset SECONDS",
                  s, kMinMotionSnr);
    return log.name + buf;
  }
  return {};
}

std::string poor_match(const AutoSync& a, const PoseLog& log) {
  char buf[320];
  if (a.correlation < kMinCorrelation) {
    std::snprintf(buf, sizeof(buf),
                  ": --clock-offset auto: the best correlation of the angular speeds is %.2f "
                  "(at least %.2f needed): does this log belong to the recording?",
                  a.correlation, kMinCorrelation);
    return log.name + buf;
  }
  if (a.runner_up > kMaxRunnerUpRatio * a.correlation) {
    std::snprintf(buf, sizeof(buf),
                  ": --clock-offset auto is ambiguous: correlation %.3f at %.6f s and %.3f at "
                  "%.6f s (a repeated motion?); give --can-log or --clock-offset SECONDS",
                  a.correlation, static_cast<double>(a.offset_ns) * 1e-9, a.runner_up,
                  static_cast<double>(a.runner_up_ns) * 1e-9);
    return log.name + buf;
  }
  return {};
}

}  // namespace

std::string sync_by_correlation(const std::vector<std::int64_t>& t_ns,
                                const std::vector<double>& speed, const PoseLog& log,
                                AutoSync* out) {
  if (t_ns.size() < 8 || speed.size() != t_ns.size()) {
    return "--clock-offset auto: the recording has too few frames to correlate";
  }
  const std::int64_t step = frame_period(t_ns);
  const std::int64_t span = t_ns.back() - t_ns.front();
  const std::int64_t log_span = log.t_ns.back() - log.t_ns.front();
  if (log_span < span + 2 * step) {
    return log.name + ": spans " + std::to_string(static_cast<double>(log_span) * 1e-9) +
           " s, shorter than the recording (" + std::to_string(static_cast<double>(span) * 1e-9) +
           " s): it cannot cover it at any clock offset";
  }
  const SpeedGrids grids = speed_grids(t_ns, speed, log, step);
  if (std::string e = too_little_motion(grids, log); !e.empty()) return e;
  const std::vector<double> c = grid_correlation(grids.r, grids.g);
  const std::size_t best =
      static_cast<std::size_t>(std::max_element(c.begin(), c.end()) - c.begin());
  const double h = static_cast<double>(step);
  AutoSync a;
  const auto [second, second_lag] = runner_up(c, best);
  a.runner_up = second;
  a.runner_up_ns = std::llround(grids.grid0 + static_cast<double>(second_lag) * h);
  // The exact correlation, over the recording's own frame intervals, near the best grid lag.
  auto f = [&](double off) { return pearson(speed, log_speed(t_ns, log, off), 1); };
  const double coarse = grids.grid0 + static_cast<double>(best) * h;
  a.offset_ns = std::llround(golden_max(f, coarse - h, coarse + h));
  a.correlation = f(static_cast<double>(a.offset_ns));
  a.motion_snr = std::min(snr(grids.r), snr(grids.g));
  if (std::string e = poor_match(a, log); !e.empty()) return e;
  *out = a;
  return {};
}

}  // namespace tacse3::tools::truth
