#include "tools/eval/plot.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "core/error.hpp"

namespace livod::eval {
namespace {

constexpr int kWidth = 1600;
constexpr int kHeight = 800;
constexpr int kMarginLeft = 80;
constexpr int kMarginRight = 30;
constexpr int kMarginTop = 60;
constexpr int kMarginBottom = 60;
constexpr double kFontScale = 0.5;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

// Colours (OpenCV images are BGR).
cv::Scalar black() {
  return {0, 0, 0};
}
cv::Scalar grid_grey() {
  return {200, 200, 200};
}
cv::Scalar ground_truth_colour() {
  return {60, 60, 60};
}
cv::Scalar estimate_colour() {
  return {200, 110, 20};
}  // blue
cv::Scalar rmse_colour() {
  return {40, 40, 220};
}  // red
cv::Scalar mean_colour() {
  return {40, 160, 40};
}  // green

struct Range {
  double lo = 0.0;
  double hi = 1.0;
  [[nodiscard]] double span() const { return hi - lo; }
};

// 1, 2 or 5 × 10^k, giving about `ticks` intervals over `span`.
double nice_step(double span, int ticks) {
  const double raw = span / ticks;
  const double magnitude = std::pow(10.0, std::floor(std::log10(raw)));
  const double n = raw / magnitude;
  const double factor = n < 1.5 ? 1.0 : (n < 3.0 ? 2.0 : (n < 7.0 ? 5.0 : 10.0));
  return factor * magnitude;
}

Range padded(double lo, double hi) {
  if (!(hi > lo)) {
    const double pad = std::max(1.0, std::abs(lo) * 0.1);
    return {lo - pad, hi + pad};
  }
  const double pad = 0.03 * (hi - lo);
  return {lo - pad, hi + pad};
}

// A rectangle of the image with linear data -> pixel mapping (y up).
class Panel {
 public:
  Panel(cv::Rect area, Range x, Range y) : area_(area), x_(x), y_(y) {}

  // Grows the narrower range so that one metre is the same number of pixels on both axes.
  void make_equal_aspect() {
    const double sx = x_.span() / area_.width;
    const double sy = y_.span() / area_.height;
    const double s = std::max(sx, sy);
    const double cx = 0.5 * (x_.lo + x_.hi);
    const double cy = 0.5 * (y_.lo + y_.hi);
    x_ = {cx - 0.5 * s * area_.width, cx + 0.5 * s * area_.width};
    y_ = {cy - 0.5 * s * area_.height, cy + 0.5 * s * area_.height};
  }

  [[nodiscard]] cv::Point pixel(double x, double y) const {
    const double u = area_.x + (x - x_.lo) / x_.span() * area_.width;
    const double v = area_.y + area_.height - (y - y_.lo) / y_.span() * area_.height;
    return {static_cast<int>(std::lround(u)), static_cast<int>(std::lround(v))};
  }

  void draw_frame(cv::Mat& img, const std::string& title, const std::string& x_label,
                  const std::string& y_label) const {
    const double x_step = nice_step(x_.span(), 8);
    for (double x = std::ceil(x_.lo / x_step) * x_step; x <= x_.hi; x += x_step) {
      const cv::Point p = pixel(x, y_.lo);
      cv::line(img, {p.x, area_.y}, {p.x, area_.y + area_.height}, grid_grey(), 1);
      const std::string label = fmt::format("{:g}", std::abs(x) < 1e-9 * x_step ? 0.0 : x);
      cv::putText(img, label, {p.x - 12, area_.y + area_.height + 18}, kFont, kFontScale, black(),
                  1, cv::LINE_AA);
    }
    const double y_step = nice_step(y_.span(), 8);
    for (double y = std::ceil(y_.lo / y_step) * y_step; y <= y_.hi; y += y_step) {
      const cv::Point p = pixel(x_.lo, y);
      cv::line(img, {area_.x, p.y}, {area_.x + area_.width, p.y}, grid_grey(), 1);
      const std::string label = fmt::format("{:g}", std::abs(y) < 1e-9 * y_step ? 0.0 : y);
      cv::putText(img, label, {area_.x - 8 - 9 * static_cast<int>(label.size()), p.y + 5}, kFont,
                  kFontScale, black(), 1, cv::LINE_AA);
    }
    cv::rectangle(img, area_, black(), 1);
    cv::putText(img, title, {area_.x, area_.y - 12}, kFont, 0.65, black(), 1, cv::LINE_AA);
    cv::putText(img, x_label, {area_.x + area_.width / 2 - 20, area_.y + area_.height + 42}, kFont,
                kFontScale, black(), 1, cv::LINE_AA);
    cv::putText(img, y_label, {area_.x - 70, area_.y - 12 + 0}, kFont, kFontScale, black(), 1,
                cv::LINE_AA);
  }

  void polyline(cv::Mat& img, const std::vector<cv::Point2d>& points, const cv::Scalar& color,
                int thickness) const {
    std::vector<cv::Point> px;
    px.reserve(points.size());
    for (const cv::Point2d& p : points) {
      const cv::Point q = pixel(p.x, p.y);
      // Consecutive samples on the same pixel add nothing but drawing time.
      if (px.empty() || px.back() != q) px.push_back(q);
    }
    if (px.size() == 1) px.push_back(px.front());
    cv::Mat clip(img, area_);
    for (cv::Point& q : px) q -= area_.tl();
    cv::polylines(clip, px, false, color, thickness, cv::LINE_AA);
  }

  void hline(cv::Mat& img, double y, const cv::Scalar& color) const {
    const cv::Point a = pixel(x_.lo, y);
    const cv::Point b = pixel(x_.hi, y);
    cv::line(img, a, b, color, 1, cv::LINE_AA);
  }

  [[nodiscard]] const cv::Rect& area() const { return area_; }

 private:
  cv::Rect area_;
  Range x_;
  Range y_;
};

void legend(cv::Mat& img, cv::Point at,
            const std::vector<std::pair<std::string, cv::Scalar>>& items) {
  for (const auto& [text, color] : items) {
    cv::line(img, at, at + cv::Point(24, 0), color, 2, cv::LINE_AA);
    cv::putText(img, text, at + cv::Point(30, 5), kFont, kFontScale, black(), 1, cv::LINE_AA);
    at.y += 20;
  }
}

// The two world axes along which the ground truth extends most, in axis order: a KITTI camera
// trajectory (y down) gives x–z, a TUM or EuRoC one usually x–y.
std::array<int, 2> plane_axes(const Trajectory& gt) {
  std::array<double, 3> extent{};
  for (int a = 0; a < 3; ++a) {
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (const RigidTransform3d& t : gt.poses) {
      lo = std::min(lo, t.translation(a));
      hi = std::max(hi, t.translation(a));
    }
    extent[static_cast<std::size_t>(a)] = hi - lo;
  }
  int drop = 0;
  for (int a = 1; a < 3; ++a) {
    if (extent[static_cast<std::size_t>(a)] < extent[static_cast<std::size_t>(drop)]) drop = a;
  }
  std::array<int, 2> axes{};
  int k = 0;
  for (int a = 0; a < 3; ++a) {
    if (a != drop) axes[static_cast<std::size_t>(k++)] = a;
  }
  return axes;
}

void draw_trajectories(cv::Mat& img, cv::Rect area, const EvalResult& r) {
  const std::array<int, 2> axes = plane_axes(r.gt);
  std::vector<cv::Point2d> gt_points;
  std::vector<cv::Point2d> est_points;
  double x_lo = std::numeric_limits<double>::infinity();
  double x_hi = -x_lo;
  double y_lo = x_lo;
  double y_hi = -x_lo;
  const auto add = [&](std::vector<cv::Point2d>& out, const RigidTransform3d& t) {
    const cv::Point2d p(t.translation(axes[0]), t.translation(axes[1]));
    x_lo = std::min(x_lo, p.x);
    x_hi = std::max(x_hi, p.x);
    y_lo = std::min(y_lo, p.y);
    y_hi = std::max(y_hi, p.y);
    out.push_back(p);
  };
  for (const RigidTransform3d& t : r.gt.poses) add(gt_points, t);
  for (const RigidTransform3d& t : r.est_aligned.poses) add(est_points, t);

  Panel panel(area, padded(x_lo, x_hi), padded(y_lo, y_hi));
  panel.make_equal_aspect();
  static constexpr std::array<const char*, 3> kAxisNames = {"x", "y", "z"};
  panel.draw_frame(img, "trajectory (top view)",
                   fmt::format("{} [m]", kAxisNames[static_cast<std::size_t>(axes[0])]),
                   fmt::format("{} [m]", kAxisNames[static_cast<std::size_t>(axes[1])]));
  panel.polyline(img, gt_points, ground_truth_colour(), 2);
  panel.polyline(img, est_points, estimate_colour(), 2);
  cv::circle(img, panel.pixel(gt_points.front().x, gt_points.front().y), 5, black(), 2,
             cv::LINE_AA);
  legend(img, {area.x + 12, area.y + 18},
         {{"ground truth", ground_truth_colour()}, {"estimate (aligned)", estimate_colour()}});
}

void draw_errors(cv::Mat& img, cv::Rect area, const EvalResult& r) {
  const bool timed = r.gt.has_stamps();
  std::vector<cv::Point2d> points;
  points.reserve(r.ape_m.size());
  for (std::size_t i = 0; i < r.ape_m.size(); ++i) {
    const double x = timed ? r.gt.stamps_s[i] - r.gt.stamps_s.front() : static_cast<double>(i);
    points.emplace_back(x, r.ape_m[i]);
  }
  const double x_max = points.back().x > 0.0 ? points.back().x : 1.0;
  const double y_max = r.ape.max > 0.0 ? r.ape.max * 1.08 : 1.0;
  const Panel panel(area, {0.0, x_max}, {0.0, y_max});
  panel.draw_frame(img, "ATE (translation) over time", timed ? "t [s]" : "pose index", "[m]");
  panel.polyline(img, points, estimate_colour(), 1);
  panel.hline(img, r.ape.rmse, rmse_colour());
  panel.hline(img, r.ape.mean, mean_colour());
  legend(img, {area.x + 12, area.y + 18},
         {{"APE", estimate_colour()},
          {fmt::format("rmse {:.4f} m", r.ape.rmse), rmse_colour()},
          {fmt::format("mean {:.4f} m", r.ape.mean), mean_colour()}});
}

}  // namespace

void write_plot(const std::filesystem::path& png_path, const EvalResult& result,
                const std::string& title) {
  if (result.gt.empty() || result.ape_m.empty()) throw Error("nothing to plot");
  cv::Mat img(kHeight, kWidth, CV_8UC3, cv::Scalar(255, 255, 255));
  const int panel_w = kWidth / 2 - kMarginLeft - kMarginRight;
  const int panel_h = kHeight - kMarginTop - kMarginBottom;
  draw_trajectories(img, {kMarginLeft, kMarginTop, panel_w, panel_h}, result);
  draw_errors(img, {kWidth / 2 + kMarginLeft, kMarginTop, panel_w, panel_h}, result);
  cv::putText(img, title, {kMarginLeft, 24}, kFont, 0.6, black(), 1, cv::LINE_AA);
  bool ok = false;
  try {
    ok = cv::imwrite(png_path.string(), img);
  } catch (const cv::Exception& e) {
    throw Error("cannot write plot '" + png_path.string() + "': " + e.what());
  }
  if (!ok) throw Error("cannot write plot '" + png_path.string() + "'");
}

}  // namespace livod::eval
