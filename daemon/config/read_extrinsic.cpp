// Reads `extrinsic:` of a sensor: T_reference_sensor as translation + rotation (quaternion,
// matrix or roll-pitch-yaw) or as one 4x4 matrix, optionally inverted, relative to the body
// frame or to another sensor.

#include "daemon/config/readers.hpp"
#include "daemon/config/rotation.hpp"

namespace livod::daemon::config_detail {

namespace {

// Any component beyond this is a unit mistake (millimetres, as in Ouster metadata), not a rig.
constexpr double kMaxTranslationComponent_m = 100.0;
// Larger lever arms exist (trucks, ships) but are unusual enough to deserve a second look.
constexpr double kLargeTranslation_m = 10.0;

std::optional<Eigen::Matrix3d> read_rotation(MapReader& r) {
  ProblemList& problems = r.problems();
  const auto wxyz = r.take("quaternion_wxyz");
  const auto xyzw = r.take("quaternion_xyzw");
  const auto matrix = r.take("matrix");
  const auto rpy = r.take("rpy_deg");
  r.finish();
  const int count = (wxyz ? 1 : 0) + (xyzw ? 1 : 0) + (matrix ? 1 : 0) + (rpy ? 1 : 0);
  if (count != 1) {
    problems.error(count == 0 ? ProblemKind::missing_key : ProblemKind::inconsistent, r.path(),
                   r.at(),
                   "needs exactly one of: quaternion_wxyz, quaternion_xyzw, matrix, rpy_deg");
    return std::nullopt;
  }
  RotationResult result;
  const Value* where = nullptr;
  if (wxyz || xyzw) {
    where = wxyz ? &*wxyz : &*xyzw;
    const auto q = parse_numbers(problems, *where, 4, 4, closed(-1.01, 1.01));
    if (!q) return std::nullopt;
    const auto& v = *q;
    result = wxyz ? rotation_from_quaternion(v[0], v[1], v[2], v[3])
                  : rotation_from_quaternion(v[3], v[0], v[1], v[2]);
  } else if (matrix) {
    where = &*matrix;
    const auto m = parse_numbers(problems, *matrix, 9, 9, closed(-1.01, 1.01));
    if (!m) return std::nullopt;
    Eigen::Matrix3d R;
    for (int i = 0; i < 9; ++i) R(i / 3, i % 3) = (*m)[static_cast<std::size_t>(i)];
    result = rotation_from_matrix(R);
  } else {
    where = &*rpy;
    const auto a = parse_numbers(problems, *rpy, 3, 3, closed(-360.0, 360.0));
    if (!a) return std::nullopt;
    result.ok = true;
    result.rotation = rotation_from_rpy_deg((*a)[0], (*a)[1], (*a)[2]);
  }
  if (!result.ok) {
    problems.error(ProblemKind::invalid_value, where->path, where->at, result.message);
    return std::nullopt;
  }
  return result.rotation;
}

std::optional<Eigen::Isometry3d> read_transform(ProblemList& problems, const Value& v) {
  const auto m = parse_numbers(problems, v, 16, 16, closed(-1e3, 1e3));
  if (!m) return std::nullopt;
  const auto& a = *m;
  constexpr double kRowTolerance = 1e-9;
  if (std::abs(a[12]) > kRowTolerance || std::abs(a[13]) > kRowTolerance ||
      std::abs(a[14]) > kRowTolerance || std::abs(a[15] - 1.0) > kRowTolerance) {
    problems.error(ProblemKind::invalid_value, v.path, v.at,
                   "the last row of a 4x4 rigid transform must be [0, 0, 0, 1]");
    return std::nullopt;
  }
  Eigen::Matrix3d R;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) R(i, j) = a[static_cast<std::size_t>(4 * i + j)];
  }
  const auto rotation = rotation_from_matrix(R);
  if (!rotation.ok) {
    problems.error(ProblemKind::invalid_value, v.path, v.at, "rotation part: " + rotation.message);
    return std::nullopt;
  }
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = rotation.rotation;
  T.translation() = Eigen::Vector3d(a[3], a[7], a[11]);
  for (int i = 0; i < 3; ++i) {
    if (std::abs(T.translation()[i]) > kMaxTranslationComponent_m) {
      problems.error(ProblemKind::out_of_range, v.path, v.at,
                     "translation component " + format_number(T.translation()[i]) +
                         " m is beyond 100 m (millimetres given as metres?)");
      return std::nullopt;
    }
  }
  return T;
}

}  // namespace

void read_extrinsic(MapReader& e, SensorConfig& sensor, SensorSite& site) {
  ProblemList& problems = e.problems();
  ExtrinsicConfig extrinsic;
  bool ok = true;
  if (const auto v = e.take("relative_to"); v && !v->node.IsNull()) {
    site.relative_to_at = v->at;
    const auto s = parse_string(problems, *v);
    ok = ok && s.has_value();
    if (s) extrinsic.relative_to = *s;
  }
  e.read("inverse", extrinsic.inverse);

  const auto transform = e.take("transform");
  const bool has_parts = e.has("translation") || e.has("rotation");
  std::optional<Eigen::Isometry3d> T;
  if (transform && has_parts) {
    problems.error(ProblemKind::inconsistent, transform->path, transform->at,
                   "give either 'transform' or 'translation' + 'rotation', not both");
    ok = false;
  } else if (transform) {
    T = read_transform(problems, *transform);
  } else {
    const auto translation_value = e.require("translation", "[x, y, z] in metres");
    std::optional<std::vector<double>> translation;
    if (translation_value) {
      translation = parse_numbers(problems, *translation_value, 3, 3,
                                  closed(-kMaxTranslationComponent_m, kMaxTranslationComponent_m));
    }
    std::optional<Eigen::Matrix3d> rotation;
    if (const auto v =
            e.require("rotation", "quaternion_wxyz, quaternion_xyzw, matrix or rpy_deg")) {
      MapReader r(problems, v->node, v->path, v->at, false);
      if (r.ok()) rotation = read_rotation(r);
    }
    if (translation && rotation) {
      T = Eigen::Isometry3d::Identity();
      T->linear() = *rotation;
      T->translation() = Eigen::Vector3d((*translation)[0], (*translation)[1], (*translation)[2]);
    }
  }
  e.finish();
  if (!ok || !T) return;
  if (T->translation().norm() > kLargeTranslation_m) {
    problems.warning(ProblemKind::out_of_range, e.path(), e.at(),
                     "the sensor is " + format_number(T->translation().norm()) +
                         " m from its reference frame; check the units (metres)");
  }
  extrinsic.T_reference_sensor = extrinsic.inverse ? T->inverse() : *T;
  sensor.extrinsic = extrinsic;
  site.extrinsic_ok = true;
}

}  // namespace livod::daemon::config_detail
