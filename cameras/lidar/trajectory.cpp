#include "cameras/lidar/trajectory.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>

#include "core/util/error.h"

namespace aperture {

Pose Pose::inverse() const {
  const glm::dquat r = glm::conjugate(rotation);
  return {-(r * translation), r};
}

glm::dmat4 Pose::matrix() const {
  glm::dmat4 m(glm::mat3_cast(rotation));
  m[3] = glm::dvec4(translation, 1.0);
  return m;
}

Pose Pose::fromMatrix(const glm::dmat4& m) {
  // Orthonormalise the rotation block (Gram-Schmidt on its columns) before converting it.
  glm::dvec3 x(m[0]), y(m[1]);
  x = glm::normalize(x);
  y = glm::normalize(y - glm::dot(y, x) * x);
  const glm::dvec3 z = glm::cross(x, y);
  const glm::dquat q = glm::normalize(glm::quat_cast(glm::dmat3(x, y, z)));
  return {glm::dvec3(m[3]), q};
}

Pose operator*(const Pose& a, const Pose& b) {
  return {a.rotation * b.translation + a.translation, glm::normalize(a.rotation * b.rotation)};
}

namespace {

// The slerp of unit quaternions a and b at fraction f, along the shorter arc; exactly a at
// f = 0 and b at f = 1.
glm::dquat slerpShort(const glm::dquat& a, glm::dquat b, double f) {
  if (f == 0) return a;
  double c = glm::dot(a, b);
  if (c < 0) {
    b = -b;
    c = -c;
  }
  if (f == 1) return b;
  if (c > 1 - 1e-12) return glm::normalize(a * (1 - f) + b * f);
  const double angle = std::acos(std::min(c, 1.0));
  const double s = std::sin(angle);
  return a * (std::sin((1 - f) * angle) / s) + b * (std::sin(f * angle) / s);
}

std::string trimmed(const std::string& s) {
  size_t a = 0, b = s.size();
  while (a < b && std::isspace(static_cast<unsigned char>(s[a]))) ++a;
  while (b > a && std::isspace(static_cast<unsigned char>(s[b - 1]))) --b;
  return s.substr(a, b - a);
}

// The numbers of a line split at whitespace (and commas), each kept as text too.
std::vector<std::string> fields(const std::string& line) {
  std::vector<std::string> out;
  std::string cur;
  for (char ch : line) {
    if (std::isspace(static_cast<unsigned char>(ch)) || ch == ',') {
      if (!cur.empty()) out.push_back(cur);
      cur.clear();
    } else {
      cur += ch;
    }
  }
  if (!cur.empty()) out.push_back(cur);
  return out;
}

double number(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v))
    throw Error(cat(where, ": '", text, "' is not a finite number"));
  return v;
}

struct Row {
  std::vector<std::string> fields;
  int line;
};

// The non-blank, non-comment rows of a file.
std::vector<Row> readRows(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw Error(cat(path, ": cannot open the trajectory file"));
  std::vector<Row> rows;
  std::string line;
  int n = 0;
  while (std::getline(in, line)) {
    ++n;
    const std::string t = trimmed(line);
    if (t.empty() || t[0] == '#') continue;
    rows.push_back({fields(t), n});
  }
  if (rows.empty()) throw Error(cat(path, ": no poses in the trajectory file"));
  return rows;
}

}  // namespace

int64_t parseTimeNs(const std::string& textIn, const std::string& what) {
  const std::string text = trimmed(textIn);
  // Plain decimals [-]digits[.digits] are read exactly; anything else through long double.
  size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) negative = text[i++] == '-';
  int64_t whole = 0;
  size_t digits = 0;
  bool plain = true;
  while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
    if (whole > (std::numeric_limits<int64_t>::max() / 10 - 9) / 1000000000) plain = false;
    whole = whole * 10 + (text[i++] - '0');
    ++digits;
  }
  int64_t fraction = 0;
  int fractionDigits = 0;
  bool roundUp = false;
  if (i < text.size() && text[i] == '.') {
    ++i;
    while (i < text.size() && std::isdigit(static_cast<unsigned char>(text[i]))) {
      if (fractionDigits < 9) {
        fraction = fraction * 10 + (text[i] - '0');
        ++fractionDigits;
      } else if (fractionDigits == 9) {
        roundUp = text[i] >= '5';
        ++fractionDigits;
      }
      ++i;
      ++digits;
    }
  }
  if (plain && digits > 0 && i == text.size()) {
    for (int k = std::min(fractionDigits, 9); k < 9; ++k) fraction *= 10;
    const int64_t ns = whole * 1000000000 + fraction + (roundUp ? 1 : 0);
    return negative ? -ns : ns;
  }
  char* end = nullptr;
  const long double v = std::strtold(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || !std::isfinite(double(v)) ||
      std::fabs(double(v)) > 9.2e9)
    throw Error(cat(what, ": '", textIn, "' is not a time in seconds"));
  return std::llround(v * 1000000000.0L);
}

std::string formatTimeNs(int64_t ns) {
  const bool negative = ns < 0;
  const uint64_t a = negative ? uint64_t(0) - uint64_t(ns) : uint64_t(ns);
  std::string frac = std::to_string(a % 1000000000u);
  frac.insert(0, 9 - frac.size(), '0');
  return (negative ? "-" : "") + std::to_string(a / 1000000000u) + "." + frac;
}

Trajectory::Trajectory(const Pose& pose) : rows_{TimedPose{0, pose}}, source_("a static pose") {}

Trajectory::Trajectory(std::vector<TimedPose> rows, std::string source, std::vector<int> lines)
    : rows_(std::move(rows)), source_(std::move(source)) {
  if (rows_.empty()) throw Error(cat(source_, ": a trajectory needs at least one pose"));
  for (size_t k = 0; k < rows_.size(); ++k) {
    const std::string where =
        k < lines.size() ? cat(source_, " line ", lines[k]) : cat(source_, " pose ", k);
    const TimedPose& r = rows_[k];
    const double qn = glm::length(r.pose.rotation);
    if (!std::isfinite(qn) || std::fabs(qn - 1) > 1e-3 ||
        !std::isfinite(glm::dot(r.pose.translation, r.pose.translation)))
      throw Error(cat(where, ": the pose is not a finite rigid transform (|q| = ", qn, ")"));
    rows_[k].pose.rotation = glm::normalize(r.pose.rotation);
    if (k > 0 && r.timeNs <= rows_[k - 1].timeNs)
      throw Error(cat(where, ": time ", formatTimeNs(r.timeNs),
                      " s is not after the one before it (", formatTimeNs(rows_[k - 1].timeNs),
                      " s): trajectory times must increase"));
  }
}

bool Trajectory::covers(int64_t timeNs) const {
  return isStatic() || (timeNs >= startNs() && timeNs <= endNs());
}

Pose Trajectory::at(int64_t timeNs) const {
  if (isStatic()) return rows_.front().pose;
  if (!covers(timeNs))
    throw Error(cat("time ", formatTimeNs(timeNs), " s is outside the trajectory ", source_, " (",
                    formatTimeNs(startNs()), " to ", formatTimeNs(endNs()), " s)"));
  const auto next = std::upper_bound(rows_.begin(), rows_.end(), timeNs,
                                     [](int64_t t, const TimedPose& r) { return t < r.timeNs; });
  if (next == rows_.end()) return rows_.back().pose;
  const TimedPose& b = *next;
  const TimedPose& a = *(next - 1);
  if (timeNs == a.timeNs) return a.pose;
  const double f = double(timeNs - a.timeNs) / double(b.timeNs - a.timeNs);
  Pose p;
  p.translation = a.pose.translation + (b.pose.translation - a.pose.translation) * f;
  p.rotation = glm::normalize(slerpShort(a.pose.rotation, b.pose.rotation, f));
  return p;
}

Trajectory loadTumTrajectory(const std::string& path) {
  std::vector<TimedPose> poses;
  std::vector<int> lines;
  for (const Row& row : readRows(path)) {
    const std::string where = cat(path, " line ", row.line);
    if (row.fields.size() != 8)
      throw Error(cat(where, ": a TUM pose row holds 8 numbers (t tx ty tz qx qy qz qw), not ",
                      row.fields.size()));
    TimedPose p;
    p.timeNs = parseTimeNs(row.fields[0], where);
    double v[7];
    for (int k = 0; k < 7; ++k) v[k] = number(row.fields[size_t(k) + 1], where);
    p.pose.translation = {v[0], v[1], v[2]};
    p.pose.rotation = glm::dquat(v[6], v[3], v[4], v[5]);
    poses.push_back(p);
    lines.push_back(row.line);
  }
  return Trajectory(std::move(poses), path, std::move(lines));
}

Trajectory loadKittiTrajectory(const std::string& posesPath, const std::string& timesPath) {
  const std::vector<Row> rows = readRows(posesPath);
  const std::vector<Row> times = readRows(timesPath);
  if (times.size() != rows.size())
    throw Error(cat(timesPath, ": ", times.size(), " times for the ", rows.size(), " poses of ",
                    posesPath, " (one time per pose)"));
  std::vector<TimedPose> poses;
  std::vector<int> lines;
  for (size_t k = 0; k < rows.size(); ++k) {
    const std::string where = cat(posesPath, " line ", rows[k].line);
    if (rows[k].fields.size() != 12)
      throw Error(cat(where, ": a KITTI pose row holds 12 numbers (3x4 [R | t]), not ",
                      rows[k].fields.size()));
    if (times[k].fields.size() != 1)
      throw Error(cat(timesPath, " line ", times[k].line, ": one time per line"));
    glm::dmat4 m(1.0);
    for (int r = 0; r < 3; ++r)
      for (int c = 0; c < 4; ++c) m[c][r] = number(rows[k].fields[size_t(r * 4 + c)], where);
    const glm::dmat3 rot(m);
    const glm::dmat3 e = glm::transpose(rot) * rot - glm::dmat3(1.0);
    double err = 0;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) err = std::max(err, std::fabs(e[c][r]));
    if (err > 1e-4 || glm::determinant(rot) < 0)
      throw Error(cat(where, ": the 3x3 block is not a rotation (|RᵀR − I| = ", err, ")"));
    TimedPose p;
    p.timeNs = parseTimeNs(times[k].fields[0], cat(timesPath, " line ", times[k].line));
    p.pose = Pose::fromMatrix(m);
    poses.push_back(p);
    lines.push_back(times[k].line);
  }
  return Trajectory(std::move(poses), cat(posesPath, " with times ", timesPath), std::move(lines));
}

Trajectory loadTrajectory(const std::string& path, const std::string& timesPath) {
  const std::vector<Row> rows = readRows(path);
  if (rows.front().fields.size() == 8) return loadTumTrajectory(path);
  if (rows.front().fields.size() == 12) {
    if (timesPath.empty())
      throw Error(cat(path, ": KITTI poses (12 numbers a row) need a times file"));
    return loadKittiTrajectory(path, timesPath);
  }
  throw Error(cat(path, " line ", rows.front().line, ": ", rows.front().fields.size(),
                  " numbers: neither a TUM row (t tx ty tz qx qy qz qw) nor a KITTI one (12)"));
}

}  // namespace aperture
