#pragma once
// Helpers shared by the Ouster tests: captures read into memory through io::PcapReader, MD5 via
// OpenSSL EVP (the digest files of ouster-sdk are MD5), and packet views for the decoder.

#include <openssl/evp.h>

#include <cstdint>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "drivers/lidar_decoder.hpp"
#include "io/pcap.hpp"

namespace livod::drivers::ouster::testutil {

struct CapturedPacket {
  std::vector<std::byte> payload;
  std::int64_t time_ns = 0;
  std::uint32_t src_ip = 0;
  std::uint16_t dst_port = 0;

  [[nodiscard]] PacketView view() const { return {payload, time_ns, dst_port}; }
};

inline std::vector<CapturedPacket> read_capture(const std::filesystem::path& path) {
  io::PcapReader reader(path);
  std::vector<CapturedPacket> out;
  while (auto d = reader.next()) {
    CapturedPacket p;
    p.payload.assign(d->payload.begin(), d->payload.end());
    p.time_ns = d->capture_time_ns;
    p.src_ip = d->src_ip;
    p.dst_port = d->dst_port;
    out.push_back(std::move(p));
  }
  return out;
}

// 169.254.238.111 -> 0xA9FEEE6F
constexpr std::uint32_t ipv4(std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
  return (a << 24) | (b << 16) | (c << 8) | d;
}

class Md5 {
 public:
  Md5() : ctx_(EVP_MD_CTX_new()) {
    if (ctx_ == nullptr || EVP_DigestInit_ex(ctx_.get(), EVP_md5(), nullptr) != 1) {
      throw std::runtime_error("EVP md5 init failed");
    }
  }
  void update(const void* data, std::size_t n) {
    if (EVP_DigestUpdate(ctx_.get(), data, n) != 1) throw std::runtime_error("EVP update failed");
  }
  template <class T>
  void update_value(T v) {
    update(&v, sizeof(v));
  }
  std::string hex() {
    unsigned char digest[EVP_MAX_MD_SIZE];
    unsigned int n = 0;
    if (EVP_DigestFinal_ex(ctx_.get(), digest, &n) != 1)
      throw std::runtime_error("EVP final failed");
    static constexpr char kHex[] = "0123456789abcdef";
    std::string s;
    for (unsigned int i = 0; i < n; ++i) {
      s.push_back(kHex[digest[i] >> 4]);
      s.push_back(kHex[digest[i] & 15]);
    }
    return s;
  }

 private:
  struct Free {
    void operator()(EVP_MD_CTX* c) const { EVP_MD_CTX_free(c); }
  };
  std::unique_ptr<EVP_MD_CTX, Free> ctx_;
};

}  // namespace livod::drivers::ouster::testutil
