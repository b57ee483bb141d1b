#pragma once
// A CAN IMU described signal by signal in the configuration (`can: {decoder: custom}`, see
// docs/drivers/imu.md): one DBC-style signal per axis (identifier, start bit, length, byte order,
// signedness, factor, offset, unit), and the identifier of the frame that completes a sample.
//
// A sample collects the six signals from their frames; it is emitted when the frame `sample_id`
// arrives and every signal has been seen since the previous sample (signals carried by the
// completing frame itself included). A completing frame with signals missing drops the sample
// (`incomplete`). Frames shorter than their signals need are `malformed`. Such IMUs carry no
// timestamp: stamp.sensor = stamp.host = the receive time of the sample's first frame.

#include <array>
#include <cstdint>
#include <vector>

#include "drivers/imu/can_signal.hpp"
#include "drivers/imu/imu_decoder.hpp"

namespace livod::imu {

enum class ImuAxis : std::uint8_t { accel_x, accel_y, accel_z, gyro_x, gyro_y, gyro_z };
enum class ImuUnit : std::uint8_t { m_s2, g, rad_s, deg_s };

struct CanSignalSpec {
  ImuAxis axis = ImuAxis::accel_x;
  std::uint32_t id = 0;  // 11-bit when <= 0x7FF, else 29-bit extended
  CanBitField bits;
  double factor = 1.0;
  double offset = 0.0;
  ImuUnit unit = ImuUnit::m_s2;
};

struct CustomCanSpec {
  std::vector<CanSignalSpec> signals;  // exactly one per axis
  std::uint32_t sample_id = 0;
  std::string name = "custom";
};

// Every problem of a spec (empty: valid): axes missing or repeated, bit fields beyond 8 bytes,
// units that do not fit the axis, factor 0, a sample_id no signal uses.
std::vector<std::string> check_spec(const CustomCanSpec& spec);

class CustomCanDecoder final : public CanImuDecoder {
 public:
  // Throws std::invalid_argument listing check_spec()'s problems.
  explicit CustomCanDecoder(CustomCanSpec spec);

  void on_frame(const CanRecord& frame, const ImuSink& sink) override;
  [[nodiscard]] const ImuDecoderCounters& counters() const override { return counters_; }
  [[nodiscard]] std::vector<std::uint32_t> frame_ids() const override { return ids_; }
  [[nodiscard]] bool has_sensor_clock() const override { return false; }
  [[nodiscard]] std::string model_name() const override { return spec_.name; }

 private:
  CustomCanSpec spec_;
  std::vector<std::uint32_t> ids_;  // distinct identifiers, sorted
  std::vector<int> needed_bytes_;   // per signal
  ImuDecoderCounters counters_;
  std::array<double, 6> values_{};
  std::uint32_t seen_ = 0;  // bit per axis
  std::int64_t first_rx_ns_ = 0;
};

// Encodes one sample with `spec` (tests, simulator): the frames in order of first appearance of
// their identifier, the completing frame last; values quantise to the signal's factor.
std::vector<CanRecord> encode_custom_sample(const CustomCanSpec& spec,
                                            const Eigen::Vector3d& accel_m_s2,
                                            const Eigen::Vector3d& gyro_rad_s);

}  // namespace livod::imu
