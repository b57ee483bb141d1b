// Reads `can:` of a can_imu sensor: a built-in frame decoder (Bosch MM7.10, SBG) or a custom one
// described signal by signal, DBC style.

#include <algorithm>
#include <set>

#include "daemon/config/readers.hpp"
#include "drivers/imu/can_signal.hpp"

namespace livod::daemon::config_detail {

namespace {

constexpr long long kMaxExtendedId = 0x1FFFFFFF;
constexpr int kFrameBits = 64;  // classic CAN: 8 data bytes

bool is_accel(CanQuantity q) {
  return q == CanQuantity::accel_x || q == CanQuantity::accel_y || q == CanQuantity::accel_z;
}

std::optional<CanSignal> read_signal(ProblemList& problems, const Value& item) {
  MapReader s(problems, item.node, item.path, item.at, false);
  if (!s.ok()) return std::nullopt;
  CanSignal signal;
  bool ok = true;
  if (const auto v = s.require("quantity", "accel_x ... gyro_z")) {
    const auto q = parse_enum<CanQuantity>(problems, *v);
    if (q) signal.quantity = *q;
    ok = ok && q.has_value();
  } else {
    ok = false;
  }
  if (const auto v = s.require("id", "the CAN identifier, e.g. 0x174")) {
    const auto id = parse_integer(problems, *v, 0, kMaxExtendedId);
    if (id) signal.id = static_cast<std::uint32_t>(*id);
    ok = ok && id.has_value();
  } else {
    ok = false;
  }
  const auto start = s.require("start_bit");
  const auto length = s.require("length", "bits");
  std::optional<long long> start_bit;
  std::optional<long long> bits;
  if (start) start_bit = parse_integer(problems, *start, 0, kFrameBits - 1);
  if (length) bits = parse_integer(problems, *length, 1, kFrameBits);
  ok = ok && start_bit && bits;
  s.read("signed", signal.is_signed);
  s.read("big_endian", signal.big_endian);
  if (start_bit && bits) {
    signal.start_bit = static_cast<int>(*start_bit);
    signal.length = static_cast<int>(*bits);
    // Intel (little-endian) signals grow upwards from start_bit; Motorola (big-endian) ones run
    // down from their most significant bit through the following bytes (DBC numbering, as the
    // decoder reads them: drivers/imu/can_signal.hpp).
    if (!signal.big_endian && *start_bit + *bits > kFrameBits) {
      problems.error(ProblemKind::out_of_range, length->path, length->at,
                     "start_bit + length = " + std::to_string(*start_bit + *bits) +
                         " is beyond the 64 bits of a CAN frame");
      ok = false;
    } else if (signal.big_endian) {
      const imu::CanBitField field{signal.start_bit, signal.length, true, signal.is_signed};
      if (const auto why = imu::check_bit_field(field, kFrameBits / 8); !why.empty()) {
        problems.error(ProblemKind::out_of_range, length->path, length->at,
                       why + " (start_bit " + std::to_string(*start_bit) +
                           " is the most "
                           "significant bit, DBC numbering)");
        ok = false;
      }
    }
  }
  if (s.read("factor", signal.factor, closed(-1e9, 1e9)) && signal.factor == 0.0) {
    problems.error(ProblemKind::out_of_range, s.child_path("factor"), s.key_at("factor"),
                   "must not be 0");
    ok = false;
  }
  s.read("offset", signal.offset, closed(-1e9, 1e9));
  if (const auto v = s.require("unit", "m_s2 or g for accelerations, rad_s or deg_s for rates")) {
    const auto unit = parse_enum<CanUnit>(problems, *v);
    if (unit) {
      signal.unit = *unit;
      const bool accel_unit = *unit == CanUnit::m_s2 || *unit == CanUnit::g;
      if (accel_unit != is_accel(signal.quantity)) {
        problems.error(ProblemKind::inconsistent, v->path, v->at,
                       std::string(enum_name(*unit)) + " is not a unit of " +
                           std::string(enum_name(signal.quantity)));
        ok = false;
      }
    } else {
      ok = false;
    }
  } else {
    ok = false;
  }
  s.finish();
  if (!ok) return std::nullopt;
  return signal;
}

}  // namespace

void read_can(MapReader& c, CanConfig& can) {
  ProblemList& problems = c.problems();
  std::optional<CanDecoder> decoder;
  if (const auto v = c.require("decoder", "bosch_mm7, sbg or custom")) {
    decoder = parse_enum<CanDecoder>(problems, *v);
  }
  if (decoder) can.decoder = *decoder;

  const auto ids = c.take("ids");
  const auto signals = c.take("signals");
  const auto sample_id = c.take("sample_id");
  c.read("fd", can.fd_frames);
  if (!decoder) {
    c.finish();
    return;
  }
  if (ids && *decoder != CanDecoder::sbg) {
    problems.error(ProblemKind::inconsistent, ids->path, ids->at,
                   "'ids' applies to the sbg decoder only");
  } else if (ids) {
    MapReader i(problems, ids->node, ids->path, ids->at);
    for (const char* key : {"info", "accel", "gyro"}) {
      if (const auto v = i.take(key); v && !v->node.IsNull()) {
        if (const auto id = parse_integer(problems, *v, 0, kMaxExtendedId)) {
          const auto value = static_cast<std::uint32_t>(*id);
          const std::string k = key;
          (k == "info"    ? can.sbg_ids.info
           : k == "accel" ? can.sbg_ids.accel
                          : can.sbg_ids.gyro) = value;
        }
      }
    }
    i.finish();
  }

  if (*decoder != CanDecoder::custom) {
    for (const auto* v : {&signals, &sample_id}) {
      if (*v) {
        problems.error(ProblemKind::inconsistent, (*v)->path, (*v)->at,
                       "applies to the custom decoder only");
      }
    }
    c.finish();
    return;
  }

  if (!signals || signals->node.IsNull()) {
    problems.error(ProblemKind::missing_key, c.child_path("signals"), c.at(),
                   "the custom decoder needs one signal per quantity (accel_x ... gyro_z)");
  } else {
    bool all_ok = true;
    std::set<CanQuantity> seen;
    for (const auto& item : sequence_items(problems, *signals)) {
      const auto signal = read_signal(problems, item);
      if (!signal) {
        all_ok = false;
        continue;
      }
      if (!seen.insert(signal->quantity).second) {
        problems.error(ProblemKind::invalid_value, item.path, item.at,
                       "a second signal for " + std::string(enum_name(signal->quantity)));
        all_ok = false;
        continue;
      }
      can.signals.push_back(*signal);
    }
    if (all_ok && signals->node.IsSequence()) {
      for (const auto& e : enum_entries<CanQuantity>()) {
        if (seen.count(e.value) == 0) {
          problems.error(ProblemKind::missing_key, signals->path, signals->at,
                         "no signal for " + std::string(e.name));
        }
      }
    }
  }
  if (!sample_id || sample_id->node.IsNull()) {
    problems.error(ProblemKind::missing_key, c.child_path("sample_id"), c.at(),
                   "the custom decoder needs the id of the frame that completes a sample");
  } else if (const auto id = parse_integer(problems, *sample_id, 0, kMaxExtendedId)) {
    can.sample_id = static_cast<std::uint32_t>(*id);
    const bool used = std::any_of(can.signals.begin(), can.signals.end(),
                                  [&](const CanSignal& s) { return s.id == can.sample_id; });
    if (!can.signals.empty() && !used) {
      problems.error(ProblemKind::inconsistent, sample_id->path, sample_id->at,
                     "no signal is carried by frame " + std::to_string(*id));
    }
  }
  c.finish();
}

}  // namespace livod::daemon::config_detail
