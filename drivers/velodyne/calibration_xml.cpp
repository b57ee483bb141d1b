// VeloView / Velodyne "db.xml" calibration files (boost::serialization XML): angles in degrees,
// distances in centimetres. Layout: boost_serialization/DB/{distLSB_, enabled_/item*,
// points_/item*/px/{id_, rotCorrection_, vertCorrection_, distCorrection_, ...}}.

#include <expat.h>

#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/units.hpp"
#include "drivers/velodyne/calibration.hpp"

namespace livod::drivers::velodyne {
namespace {

constexpr double kCmToM = 0.01;

struct XmlState {
  std::vector<std::string> path;  // open elements, outermost first
  std::string text;               // character data of the innermost element
  std::optional<double> dist_lsb_cm;
  std::vector<int> enabled;
  std::map<std::string, std::string> px;  // fields of the <px> being read
  std::vector<std::map<std::string, std::string>> points;
};

bool path_ends_with(const std::vector<std::string>& path, std::initializer_list<const char*> tail) {
  if (path.size() < tail.size()) return false;
  auto it = path.end() - static_cast<std::ptrdiff_t>(tail.size());
  for (const char* name : tail) {
    if (*it++ != name) return false;
  }
  return true;
}

void on_start(void* user, const XML_Char* name, const XML_Char** /*attributes*/) {
  auto* s = static_cast<XmlState*>(user);
  s->path.emplace_back(name);
  s->text.clear();
  if (s->path.back() == "px") s->px.clear();
}

void on_end(void* user, const XML_Char* /*name*/) {
  auto* s = static_cast<XmlState*>(user);
  if (path_ends_with(s->path, {"DB", "distLSB_"})) {
    double v = 0.0;
    const auto* begin = s->text.data();
    if (std::from_chars(begin, begin + s->text.size(), v).ec == std::errc{}) s->dist_lsb_cm = v;
  } else if (path_ends_with(s->path, {"DB", "enabled_", "item"})) {
    int v = 0;
    const auto* begin = s->text.data();
    if (std::from_chars(begin, begin + s->text.size(), v).ec != std::errc{}) v = -1;
    s->enabled.push_back(v);
  } else if (path_ends_with(s->path, {"points_", "item", "px"})) {
    s->points.push_back(s->px);
  } else if (s->path.size() >= 2 && s->path[s->path.size() - 2] == "px") {
    s->px[s->path.back()] = s->text;
  }
  s->path.pop_back();
  s->text.clear();
}

void on_text(void* user, const XML_Char* data, int length) {
  auto* s = static_cast<XmlState*>(user);
  for (int i = 0; i < length; ++i) {
    const char c = data[i];
    if (c != ' ' && c != '\t' && c != '\r' && c != '\n') s->text.push_back(c);
  }
}

double field(const std::map<std::string, std::string>& px, const char* key,
             const std::string& source) {
  const auto it = px.find(key);
  if (it == px.end() || it->second.empty()) return 0.0;  // VeloView treats missing as zero
  double v = 0.0;
  const auto* begin = it->second.data();
  const auto [end, ec] = std::from_chars(begin, begin + it->second.size(), v);
  if (ec != std::errc{} || end != begin + it->second.size() || !std::isfinite(v)) {
    throw Error(source + ": <" + key + "> is not a number: '" + it->second + "'");
  }
  return v;
}

}  // namespace

Calibration parse_veloview_xml(std::string_view text, const std::string& source) {
  XmlState state;
  const std::unique_ptr<XML_ParserStruct, decltype(&XML_ParserFree)> parser(
      XML_ParserCreate(nullptr), &XML_ParserFree);
  if (!parser) throw Error(source + ": cannot create an XML parser");
  XML_SetUserData(parser.get(), &state);
  XML_SetElementHandler(parser.get(), &on_start, &on_end);
  XML_SetCharacterDataHandler(parser.get(), &on_text);
  if (text.size() > static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw Error(source + ": calibration file too large");
  }
  if (XML_Parse(parser.get(), text.data(), static_cast<int>(text.size()), XML_TRUE) ==
      XML_STATUS_ERROR) {
    const auto offset = XML_GetCurrentByteIndex(parser.get());
    throw FormatError(
        source, offset < 0 ? 0 : static_cast<std::uint64_t>(offset),
        std::string("invalid XML: ") + XML_ErrorString(XML_GetErrorCode(parser.get())));
  }
  if (state.points.empty()) throw Error(source + ": no <points_> entries (not a VeloView file?)");

  // VeloView counts the lasers as the enabled_ items set to 1; the file may list 64 entries.
  std::size_t lasers = state.points.size();
  if (!state.enabled.empty()) {
    lasers = 0;
    for (const int e : state.enabled) lasers += e == 1 ? 1 : 0;
  }

  Calibration calibration;
  calibration.source = source;
  calibration.lasers.resize(lasers);
  std::vector<bool> seen(lasers, false);
  for (const auto& px : state.points) {
    const double id_value = field(px, "id_", source);
    if (id_value < 0 || id_value != std::floor(id_value)) {
      throw Error(source + ": invalid laser id " + std::to_string(id_value));
    }
    const auto id = static_cast<std::size_t>(id_value);
    if (id >= lasers) continue;  // disabled lasers of a 64-entry table
    auto& l = calibration.lasers[id];
    l.rot_correction_rad = field(px, "rotCorrection_", source) * kDegToRad;
    l.vert_correction_rad = field(px, "vertCorrection_", source) * kDegToRad;
    l.dist_correction_m = field(px, "distCorrection_", source) * kCmToM;
    l.dist_correction_x_m = field(px, "distCorrectionX_", source) * kCmToM;
    l.dist_correction_y_m = field(px, "distCorrectionY_", source) * kCmToM;
    l.vert_offset_m = field(px, "vertOffsetCorrection_", source) * kCmToM;
    l.horiz_offset_m = field(px, "horizOffsetCorrection_", source) * kCmToM;
    l.focal_distance_m = field(px, "focalDistance_", source) * kCmToM;
    l.focal_slope = field(px, "focalSlope_", source);
    seen[id] = true;
  }
  for (std::size_t i = 0; i < lasers; ++i) {
    if (!seen[i]) throw Error(source + ": no <px> entry for enabled laser " + std::to_string(i));
  }
  if (state.dist_lsb_cm) calibration.distance_resolution_m = *state.dist_lsb_cm * kCmToM;
  return calibration;
}

}  // namespace livod::drivers::velodyne
