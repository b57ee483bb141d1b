#include "daemon/devices/imu_decoders.hpp"

#include "core/error.hpp"
#include "drivers/imu/bosch_mm7.hpp"
#include "drivers/imu/custom_can.hpp"
#include "drivers/imu/sbg_can.hpp"
#include "drivers/imu/xsens_mtdata2.hpp"

namespace livod::daemon::devices {
namespace {

imu::ImuAxis to_axis(CanQuantity q) {
  switch (q) {
    case CanQuantity::accel_x:
      return imu::ImuAxis::accel_x;
    case CanQuantity::accel_y:
      return imu::ImuAxis::accel_y;
    case CanQuantity::accel_z:
      return imu::ImuAxis::accel_z;
    case CanQuantity::gyro_x:
      return imu::ImuAxis::gyro_x;
    case CanQuantity::gyro_y:
      return imu::ImuAxis::gyro_y;
    case CanQuantity::gyro_z:
      return imu::ImuAxis::gyro_z;
  }
  return imu::ImuAxis::accel_x;
}

imu::ImuUnit to_unit(CanUnit u) {
  switch (u) {
    case CanUnit::m_s2:
      return imu::ImuUnit::m_s2;
    case CanUnit::g:
      return imu::ImuUnit::g;
    case CanUnit::rad_s:
      return imu::ImuUnit::rad_s;
    case CanUnit::deg_s:
      return imu::ImuUnit::deg_s;
  }
  return imu::ImuUnit::m_s2;
}

}  // namespace

std::unique_ptr<imu::CanImuDecoder> make_can_imu_decoder(const CanConfig& can,
                                                         const std::string& sensor) {
  switch (can.decoder) {
    case CanDecoder::sbg:
      return std::make_unique<imu::SbgCanDecoder>(
          imu::SbgCanIds{can.sbg_ids.info, can.sbg_ids.accel, can.sbg_ids.gyro});
    case CanDecoder::bosch_mm7:
      return std::make_unique<imu::BoschMm7Decoder>();
    case CanDecoder::custom: {
      imu::CustomCanSpec spec;
      spec.name = "custom CAN IMU '" + sensor + "'";
      spec.sample_id = can.sample_id;
      for (const CanSignal& s : can.signals) {
        spec.signals.push_back({to_axis(s.quantity), s.id,
                                imu::CanBitField{s.start_bit, s.length, s.big_endian, s.is_signed},
                                s.factor, s.offset, to_unit(s.unit)});
      }
      const auto problems = imu::check_spec(spec);
      if (!problems.empty()) {
        std::string text = "sensor '" + sensor + "': invalid custom CAN decoder:";
        for (const auto& p : problems) text += " " + p + ";";
        throw Error(text);
      }
      return std::make_unique<imu::CustomCanDecoder>(std::move(spec));
    }
  }
  throw Error("sensor '" + sensor + "': unknown CAN decoder");
}

std::unique_ptr<imu::StreamImuDecoder> make_serial_imu_decoder(const SerialConfig& serial,
                                                               const std::string& sensor) {
  switch (serial.protocol) {
    case SerialProtocol::xsens_mtdata2:
      return std::make_unique<imu::XsensMtData2Decoder>();
    case SerialProtocol::vectornav_binary:
      break;
  }
  throw Error("sensor '" + sensor + "': serial protocol " +
              std::string(enum_name(serial.protocol)) + " is not implemented (xsens_mtdata2 is)");
}

}  // namespace livod::daemon::devices
