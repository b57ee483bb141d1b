#pragma once
// CRC-64/XZ (ECMA-182 polynomial, reflected, init and xorout all ones): the footer checksum of
// Ouster FW >= 2.5 lidar, IMU and zone packets (sensor-protocols.md §3.3). Check value for
// "123456789" is 0x995DC9BBDF1939FA.

#include <cstdint>
#include <span>

namespace livod::drivers::ouster {

[[nodiscard]] std::uint64_t crc64_xz(std::span<const std::byte> bytes);

}  // namespace livod::drivers::ouster
