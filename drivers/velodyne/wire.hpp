#pragma once
// Byte layout of Velodyne UDP payloads (§4.1, §4.2 of shared/docs/sensor-protocols.md), the
// little-endian readers used by the packet decoders and the writers used by packet encoders (the
// simulator, tests). Callers check lengths before reading or writing.

#include <cstddef>
#include <cstdint>
#include <span>

namespace livod::drivers::velodyne::wire {

inline constexpr std::size_t kDataPacketSize = 1206;
inline constexpr std::size_t kPositionPacketSize = 512;

inline constexpr int kBlocksPerPacket = 12;
inline constexpr int kChannelsPerBlock = 32;
inline constexpr int kReturnsPerPacket = kBlocksPerPacket * kChannelsPerBlock;
inline constexpr std::size_t kBlockSize = 100;         // flag 2 + azimuth 2 + 32 x (2 + 1)
inline constexpr std::size_t kChannelSize = 3;         // distance u16 + reflectivity u8
inline constexpr std::size_t kTimestampOffset = 1200;  // u32 microseconds since top of hour
inline constexpr std::size_t kReturnModeOffset = 1204;
inline constexpr std::size_t kFactoryByteOffset = 1205;

// Block flags as little-endian u16 (bytes FF EE, FF DD, FF CC, FF BB).
inline constexpr std::uint16_t kBank0Flag = 0xEEFF;
inline constexpr std::uint16_t kBank1Flag = 0xDDFF;
inline constexpr std::uint16_t kBank2Flag = 0xCCFF;
inline constexpr std::uint16_t kBank3Flag = 0xBBFF;

inline constexpr std::uint16_t kAzimuthUnitsPerTurn = 36000;  // 0.01 degree
inline constexpr std::uint32_t kMicrosecondsPerHour = 3'600'000'000U;

// Position packet (VDEC src/telemetry_packet.cpp; VeloView vtkVelodyneHDLPositionReader).
inline constexpr std::size_t kImuWordsOffset = 14;  // 3 sensors x (gyro, temp, accel x, accel y)
inline constexpr std::size_t kImuWordsPerSensor = 4;
inline constexpr std::size_t kImuSensors = 3;
inline constexpr std::size_t kPositionTimestampOffset = 198;
inline constexpr std::size_t kPpsStatusOffset = 202;
inline constexpr std::size_t kNmeaOffset = 206;

inline std::uint8_t u8(std::span<const std::byte> b, std::size_t offset) {
  return static_cast<std::uint8_t>(b[offset]);
}
inline std::uint16_t u16le(std::span<const std::byte> b, std::size_t offset) {
  return static_cast<std::uint16_t>(u8(b, offset) | (u8(b, offset + 1) << 8));
}
inline std::uint32_t u32le(std::span<const std::byte> b, std::size_t offset) {
  return static_cast<std::uint32_t>(u8(b, offset)) |
         (static_cast<std::uint32_t>(u8(b, offset + 1)) << 8) |
         (static_cast<std::uint32_t>(u8(b, offset + 2)) << 16) |
         (static_cast<std::uint32_t>(u8(b, offset + 3)) << 24);
}

inline void put_u16le(std::span<std::byte> b, std::size_t offset, std::uint16_t v) {
  b[offset] = static_cast<std::byte>(v & 0xFF);
  b[offset + 1] = static_cast<std::byte>(v >> 8);
}
inline void put_u32le(std::span<std::byte> b, std::size_t offset, std::uint32_t v) {
  for (std::size_t i = 0; i < 4; ++i) b[offset + i] = static_cast<std::byte>((v >> (8 * i)) & 0xFF);
}

}  // namespace livod::drivers::velodyne::wire
