#include "haptics/devices.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>
#include <stdexcept>
#include <string>

namespace fetouch::haptics {

namespace {

// A number in a message, as short as it reads exactly enough ("0.001", "1e+05").
std::string number(double x) {
  std::ostringstream out;
  out << std::setprecision(6) << x;
  return out.str();
}

// A line of a file as quoted in a message: at most 60 characters, control and non-ASCII bytes as '?'.
std::string excerpt(const std::string& line) {
  std::string out = line.size() <= 60 ? line : line.substr(0, 57) + "...";
  for (char& c : out)
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
  return out;
}

}  // namespace

Eigen::Vector3d Trajectory::at(double t) const {
  if (times_s.empty()) return Eigen::Vector3d::Zero();
  if (t <= times_s.front()) return positions_m.front();
  if (t >= times_s.back()) return positions_m.back();
  const auto after = std::upper_bound(times_s.begin(), times_s.end(), t);
  const std::size_t i = static_cast<std::size_t>(after - times_s.begin());
  const double s = (t - times_s[i - 1]) / (times_s[i] - times_s[i - 1]);
  return (1 - s) * positions_m[i - 1] + s * positions_m[i];
}

std::vector<Eigen::Vector3d> Trajectory::resampled(double period_s) const {
  std::vector<Eigen::Vector3d> out;
  if (times_s.empty()) return out;
  // Tick k at t0 + k T; the last tick is the one at (or, by rounding, just before) the last time.
  const long ticks = static_cast<long>(std::floor(duration_s() / period_s + 1e-9)) + 1;
  out.reserve(static_cast<std::size_t>(ticks));
  for (long k = 0; k < ticks; ++k) out.push_back(at(times_s.front() + k * period_s));
  return out;
}

std::pair<double, double> Trajectory::longest_hold() const {
  std::pair<double, double> best{0, 0};
  for (std::size_t i = 1; i < times_s.size(); ++i)
    if ((positions_m[i] - positions_m[i - 1]).norm() < 1e-12 && times_s[i] - times_s[i - 1] > best.second - best.first)
      best = {times_s[i - 1], times_s[i]};
  return best;
}

void Trajectory::check(const std::string& source) const {
  if (times_s.size() != positions_m.size())
    throw std::runtime_error(source + ": " + std::to_string(times_s.size()) + " times but " +
                             std::to_string(positions_m.size()) + " positions");
  for (std::size_t i = 0; i < times_s.size(); ++i) {
    const std::string row = source + ": sample " + std::to_string(i);
    if (!std::isfinite(times_s[i]) || !positions_m[i].allFinite()) throw std::runtime_error(row + " is not finite");
    if (i == 0 && times_s[i] < 0)
      throw std::runtime_error(row + ": time " + number(times_s[i]) + " s; times are seconds since the start, >= 0");
    if (i > 0 && !(times_s[i] > times_s[i - 1]))
      throw std::runtime_error(row + ": time " + number(times_s[i]) + " s is not after the previous " +
                               number(times_s[i - 1]) + " s (times must strictly increase)");
    if (i > 0 && times_s[i] - times_s[i - 1] < kMinStepS)
      throw std::runtime_error(row + ": " + number(times_s[i] - times_s[i - 1]) +
                               " s after the previous sample; samples are at least 1 us apart");
    if (positions_m[i].norm() > kMaxReachM)
      throw std::runtime_error(row + ": a point " + number(positions_m[i].norm()) +
                               " m from the origin (at most 10 m; positions are in metres)");
    if (i > 0) {
      const double speed = (positions_m[i] - positions_m[i - 1]).norm() / (times_s[i] - times_s[i - 1]);
      if (speed > kMaxSpeedMPerS)
        throw std::runtime_error(row + ": the probe moves at " + number(speed) +
                                 " m/s from the previous sample; a hand moves it at most 10 m/s (positions in metres, times in seconds)");
    }
  }
  if (duration_s() > kMaxDurationS)
    throw std::runtime_error(source + ": lasts " + number(duration_s()) + " s; a replay lasts at most " +
                             number(kMaxDurationS) + " s");
}

Trajectory read_trajectory_csv(const std::filesystem::path& path) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error))
    throw std::runtime_error(path.string() + ": not a regular file (a trajectory is a CSV file, not a folder, FIFO or device)");
  if (std::filesystem::file_size(path, error) > (512u << 20))
    throw std::runtime_error(path.string() + ": over 512 MB, too large for a trajectory");
  std::ifstream in(path);
  if (!in) throw std::runtime_error(path.string() + ": cannot be opened");
  Trajectory t;
  std::string line;
  int number = 0;
  const auto fail = [&](const std::string& what) {
    throw std::runtime_error(path.string() + ":" + std::to_string(number) + ": " + what);
  };
  while (std::getline(in, line)) {
    ++number;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    if (t.times_s.empty() && std::isalpha(static_cast<unsigned char>(line[first]))) continue;  // a header
    std::string cell;
    std::istringstream cells(line);
    double v[4];
    int n = 0;
    const std::string not_four = "expected four numbers t, x, y, z, found '" + excerpt(line) + "'";
    while (std::getline(cells, cell, ',')) {
      std::istringstream number_in(cell);
      double x;
      std::string rest;
      if (n >= 4 || !(number_in >> x) || (number_in >> rest)) fail(not_four);
      if (!std::isfinite(x)) fail("a value is not finite: '" + excerpt(cell) + "'");
      v[n++] = x;
    }
    if (n != 4) fail(not_four);
    if (!t.times_s.empty() && !(v[0] > t.times_s.back()))
      fail("time " + std::to_string(v[0]) + " s is not after the previous row's " + std::to_string(t.times_s.back()) + " s");
    t.times_s.push_back(v[0]);
    t.positions_m.emplace_back(v[1], v[2], v[3]);
  }
  if (t.times_s.size() < 2)
    throw std::runtime_error(path.string() + ": a trajectory needs at least two rows of t, x, y, z (found " +
                             std::to_string(t.times_s.size()) + ")");
  t.check(path.string());
  return t;
}

void write_trajectory_csv(const Trajectory& trajectory, const std::filesystem::path& path, const std::string& comment) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot be written");
  std::istringstream lines(comment);
  for (std::string line; std::getline(lines, line);) out << "# " << line << "\n";
  out << "t_s,x_m,y_m,z_m\n" << std::setprecision(17);
  for (std::size_t i = 0; i < trajectory.times_s.size(); ++i) {
    const auto& p = trajectory.positions_m[i];
    out << trajectory.times_s[i] << ',' << p.x() << ',' << p.y() << ',' << p.z() << "\n";
  }
  if (!out) throw std::runtime_error(path.string() + ": could not be written");
}

Trajectory scripted_path(PathShape shape, const PathSettings& s) {
  if (!(s.normal.norm() > 0)) throw std::invalid_argument("--normal: the normal must not be zero");
  if (!(s.approach_m >= 0) || !(s.depth_m >= 0)) throw std::invalid_argument("path: lengths must not be negative");
  for (double d : {s.approach_s, s.press_s, s.hold_s, s.release_s, s.retreat_s})
    if (!(d > 0)) throw std::invalid_argument("--times: every duration must be positive");
  const Eigen::Vector3d n = s.normal.normalized();
  const Eigen::Vector3d moved = shape == PathShape::slide ? s.slide_m : Eigen::Vector3d::Zero();
  Trajectory t;
  double time = 0;
  const auto row = [&](double after, const Eigen::Vector3d& p) {
    time += after;
    t.times_s.push_back(time);
    t.positions_m.push_back(p);
  };
  row(0, s.point + s.approach_m * n);
  row(s.approach_s, s.point);
  row(s.press_s, s.point - s.depth_m * n);
  row(s.hold_s, s.point + moved - s.depth_m * n);
  row(s.release_s, s.point + moved);
  row(s.retreat_s, s.point + moved + s.approach_m * n);
  return t;
}

ReplayDevice::ReplayDevice(const Trajectory& trajectory, double period_s)
    : points_(trajectory.resampled(period_s)), period_s_(period_s) {
  if (points_.empty()) throw std::invalid_argument("replay: an empty trajectory");
}

DeviceState ReplayDevice::read() noexcept {
  const long last = static_cast<long>(points_.size()) - 1;
  const long i = std::min<long>(tick_, last), before = std::min<long>(std::max<long>(tick_ - 1, 0), last);
  ++tick_;
  DeviceState s;
  s.position_m = points_[static_cast<std::size_t>(i)];
  s.velocity_m_per_s = (s.position_m - points_[static_cast<std::size_t>(before)]) / period_s_;
  return s;
}

namespace {

// exp(M) of a small matrix by scaling and squaring a Taylor series (to machine precision).
template <int N>
Eigen::Matrix<double, N, N> exponential(const Eigen::Matrix<double, N, N>& m) {
  using Matrix = Eigen::Matrix<double, N, N>;
  const double norm = m.cwiseAbs().rowwise().sum().maxCoeff();
  const int squarings = norm > 0.5 ? static_cast<int>(std::ceil(std::log2(norm / 0.5))) : 0;
  const Matrix a = m / std::pow(2.0, squarings);
  Matrix sum = Matrix::Identity(), term = Matrix::Identity();
  for (int k = 1; k <= 24; ++k) {
    term = term * a / k;
    sum += term;
  }
  for (int s = 0; s < squarings; ++s) sum = sum * sum;
  return sum;
}

void check_hand(const HandParameters& hand) {
  if (!(hand.mass_kg > 0) || !(hand.stiffness_n_per_m > 0) || !(hand.damping_n_s_per_m >= 0))
    throw std::invalid_argument("operator: the hand's mass and stiffness must be positive and its damping not negative");
  if (hand.model == HandModelKind::stylus &&
      (!(hand.handle_mass_kg > 0) || !(hand.arm_stiffness_n_per_m > 0) || !(hand.arm_damping_n_s_per_m >= 0)))
    throw std::invalid_argument("operator: a stylus hand's handle mass and arm stiffness must be positive and its arm damping not negative");
}

}  // namespace

// ZOH discretisation of the hand for the state (x_d, v_d, x_h, v_h) and the inputs (F, x_t, v_t),
// with the grip (one_mass: the hand's spring and damper, x_h and v_h idle; stylus: k1, b1)
// multiplied by `grip`: exp of the 7 x 7 augmented matrix [A B; 0 0] T.
void hand_transition(const HandParameters& hand, double grip, double period_s, Eigen::Matrix4d& phi,
                     Eigen::Matrix<double, 4, 3>& gamma) {
  Eigen::Matrix<double, 7, 7> m = Eigen::Matrix<double, 7, 7>::Zero();
  const double k1 = grip * hand.stiffness_n_per_m, b1 = grip * hand.damping_n_s_per_m;
  m(0, 1) = 1;
  if (hand.model == HandModelKind::one_mass) {
    const double md = hand.mass_kg;
    m(1, 0) = -k1 / md, m(1, 1) = -b1 / md;
    m(1, 4) = 1 / md, m(1, 5) = k1 / md, m(1, 6) = b1 / md;
  } else {
    const double md = hand.handle_mass_kg, mh = hand.mass_kg;
    const double k2 = hand.arm_stiffness_n_per_m, b2 = hand.arm_damping_n_s_per_m;
    m(1, 0) = -k1 / md, m(1, 1) = -b1 / md, m(1, 2) = k1 / md, m(1, 3) = b1 / md, m(1, 4) = 1 / md;
    m(2, 3) = 1;
    m(3, 0) = k1 / mh, m(3, 1) = b1 / mh, m(3, 2) = -(k1 + k2) / mh, m(3, 3) = -(b1 + b2) / mh;
    m(3, 5) = k2 / mh, m(3, 6) = b2 / mh;
  }
  const Eigen::Matrix<double, 7, 7> e = exponential<7>(Eigen::Matrix<double, 7, 7>(m * period_s));
  phi = e.topLeftCorner<4, 4>();
  gamma = e.topRightCorner<4, 3>();
}

namespace {

void check_event(const HandEvent& e) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("operator: " + what); };
  if (!(e.at_s >= 0) || !std::isfinite(e.at_s)) fail("an event's time must be 0 s or later, not " + std::to_string(e.at_s));
  switch (e.kind) {
    case HandEventKind::release: break;
    case HandEventKind::grip:
      if (!(e.factor > 0) || !std::isfinite(e.factor)) fail("a grip's factor must be positive, not " + std::to_string(e.factor));
      if (!(e.ramp_s >= 0) || !std::isfinite(e.ramp_s)) fail("a grip's ramp must be 0 s or longer, not " + std::to_string(e.ramp_s));
      break;
    case HandEventKind::tremor:
      if (!(e.frequency_hz > 0) || !std::isfinite(e.frequency_hz)) fail("a tremor's frequency must be positive");
      if (!(e.amplitude_m >= 0) || !std::isfinite(e.amplitude_m)) fail("a tremor's amplitude must be 0 or more");
      [[fallthrough]];
    case HandEventKind::impact:
      if (!(e.direction.norm() > 0) || !e.direction.allFinite()) fail("a tremor's or impact's direction must not be zero");
      if (!std::isfinite(e.speed_m_per_s)) fail("an impact's speed must be finite");
      break;
  }
}

}  // namespace

HandParameters stylus_hand() {
  HandParameters hand;
  hand.model = HandModelKind::stylus;
  hand.mass_kg = 0.21;
  hand.stiffness_n_per_m = 575;
  hand.damping_n_s_per_m = 1.3;
  hand.handle_mass_kg = 0.045;
  hand.arm_stiffness_n_per_m = 175;
  hand.arm_damping_n_s_per_m = 11;
  return hand;
}

const char* to_string(HandModelKind model) { return model == HandModelKind::stylus ? "stylus" : "one_mass"; }

VirtualOperator::VirtualOperator(const Trajectory& trajectory, const HandParameters& hand, double period_s,
                                 const std::vector<HandEvent>& events)
    : targets_(trajectory.resampled(period_s)) {
  check_hand(hand);
  if (targets_.empty()) throw std::invalid_argument("operator: an empty trajectory");
  for (const HandEvent& e : events) check_event(e);
  const std::size_t n = targets_.size();
  const auto tick_of = [period_s](double t) { return static_cast<std::size_t>(std::llround(t / period_s)); };
  std::vector<HandEvent> ordered = events;
  std::stable_sort(ordered.begin(), ordered.end(), [](const HandEvent& a, const HandEvent& b) { return a.at_s < b.at_s; });

  // Tremor moves the target; the target's velocity follows from it.
  for (const HandEvent& e : ordered)
    if (e.kind == HandEventKind::tremor)
      for (std::size_t k = tick_of(e.at_s); k < n; ++k)
        targets_[k] += e.amplitude_m * std::sin(2 * M_PI * e.frequency_hz * (double(k) * period_s - e.at_s)) *
                       e.direction.normalized();
  // The target's velocity, by central differences (one-sided at the ends).
  target_velocities_.assign(n, Eigen::Vector3d::Zero());
  for (std::size_t k = 0; k < n && n > 1; ++k) {
    const std::size_t a = k == 0 ? 0 : k - 1, b = k + 1 == n ? k : k + 1;
    target_velocities_[k] = (targets_[b] - targets_[a]) / (double(b - a) * period_s);
  }

  // The grip's multiplier on k and b, tick by tick: each event rewrites it from its own tick on.
  std::vector<double> multiplier(n, 1.0);
  for (const HandEvent& e : ordered) {
    const std::size_t from = tick_of(e.at_s);
    if (from >= n) continue;
    if (e.kind == HandEventKind::release) {
      std::fill(multiplier.begin() + static_cast<long>(from), multiplier.end(), 0.0);
    } else if (e.kind == HandEventKind::grip) {
      const double base = multiplier[from];
      const double ramp = std::max(1.0, std::round(e.ramp_s / period_s));
      for (std::size_t k = from; k < n; ++k)
        multiplier[k] = base * (1 + (e.factor - 1) * std::min(1.0, double(k - from + 1) / ramp));
    } else if (e.kind == HandEventKind::impact) {
      impact_ticks_.push_back(static_cast<long>(from));
      impact_velocities_.push_back(e.speed_m_per_s * e.direction.normalized());
    }
  }
  grip_of_tick_.resize(n);
  std::vector<double> known;
  for (std::size_t k = 0; k < n; ++k) {
    const auto at = std::find(known.begin(), known.end(), multiplier[k]);
    if (at != known.end()) {
      grip_of_tick_[k] = static_cast<int>(at - known.begin());
      continue;
    }
    Grip g;
    hand_transition(hand, multiplier[k], period_s, g.phi, g.gamma);
    grip_of_tick_[k] = static_cast<int>(known.size());
    known.push_back(multiplier[k]);
    grips_.push_back(g);
  }
  position_ = hand_position_ = targets_.front();
  velocity_.setZero();
}

DeviceState VirtualOperator::read() noexcept {
  if (tick_ > 0) {
    // Over the last tick: its target, the grip then and the force rendered at it, held.
    const std::size_t k = static_cast<std::size_t>(std::min<long>(tick_ - 1, static_cast<long>(targets_.size()) - 1));
    const Grip& g = grips_[static_cast<std::size_t>(grip_of_tick_[k])];
    const Eigen::Vector3d force = force_.allFinite() ? force_ : Eigen::Vector3d::Zero();
    for (int d = 0; d < 3; ++d) {
      const Eigen::Vector4d state(position_[d], velocity_[d], hand_position_[d], hand_velocity_[d]);
      const Eigen::Vector4d next = g.phi * state + g.gamma * Eigen::Vector3d(force[d], targets_[k][d], target_velocities_[k][d]);
      position_[d] = next[0], velocity_[d] = next[1], hand_position_[d] = next[2], hand_velocity_[d] = next[3];
    }
  }
  // An impact: the hand arrives at its speed from this tick on (the handle with it).
  while (next_impact_ < impact_ticks_.size() && impact_ticks_[next_impact_] <= tick_)
    velocity_ = hand_velocity_ = impact_velocities_[next_impact_++];
  ++tick_;
  DeviceState s;
  s.position_m = position_;
  s.velocity_m_per_s = velocity_;
  return s;
}

CursorOperator::CursorOperator(const Eigen::Vector3d& start, const HandParameters& hand, double period_s)
    : cursor_(start), target_(start), position_(start), stiffness_(hand.stiffness_n_per_m) {
  check_hand(hand);
  if (hand.model != HandModelKind::one_mass) throw std::invalid_argument("operator: the mouse's hand is one mass, not a stylus grip");
  // One mass: (x, v) and its response to the force alone; the cursor's pull is k times that.
  Eigen::Matrix4d phi;
  Eigen::Matrix<double, 4, 3> gamma;
  hand_transition(hand, 1.0, period_s, phi, gamma);
  phi_ = phi.topLeftCorner<2, 2>();
  gamma_ = gamma.block<2, 1>(0, 0);
}

DeviceState CursorOperator::read() noexcept {
  if (cursor_.take()) target_ = cursor_.front();
  // Over the last tick: the cursor (still, as far as the hand knows: no damping on its motion) and
  // the force rendered, held.
  const Eigen::Vector3d force = force_.allFinite() ? force_ : Eigen::Vector3d::Zero();
  const Eigen::Vector3d u = stiffness_ * target_ + force;
  for (int d = 0; d < 3; ++d) {
    const double x = phi_(0, 0) * position_[d] + phi_(0, 1) * velocity_[d] + gamma_[0] * u[d];
    const double v = phi_(1, 0) * position_[d] + phi_(1, 1) * velocity_[d] + gamma_[1] * u[d];
    position_[d] = x, velocity_[d] = v;
  }
  DeviceState s;
  s.position_m = position_;
  s.velocity_m_per_s = velocity_;
  return s;
}

}  // namespace fetouch::haptics
