// LCM fingerprints: the generated bot_core::pose_t must carry libbot2's fingerprint, so that
// Pronto, Director and libbot tools decode livod's POSE_BODY. Checked two independent ways:
//  * LCM's fingerprint algorithm (LCM type specification, "Fingerprint computation") implemented
//    here from the field list of libbot2's bot_core.pose_t;
//  * lcm-gen run on libbot2's definition in a temporary folder, its hash constant read back.
// Both must equal bot_core::pose_t::getHash(); a renamed, retyped, reordered or resized field in
// lcmtypes/bot_core/pose_t.lcm makes the test fail (the negative controls below show it would).

#include <gtest/gtest.h>

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "lcmtypes/bot_core/pose_t.hpp"
#include "lcmtypes/livod/pose_t.hpp"
#include "tests/support/data_dir.hpp"
#include "tests/support/process.hpp"

namespace livod {
namespace {

// ---- LCM's fingerprint algorithm
// -----------------------------------------------------------------

struct Member {
  std::string name;
  std::string type;                // primitive type name ("double", "string", ...)
  std::vector<std::string> sizes;  // one per dimension; fixed sizes only here
};

std::uint64_t hash_update(std::uint64_t v, char c) {
  // ((v << 8) ^ (v >> 55)) + c, with v a signed 64-bit value (arithmetic right shift) and c a
  // signed char, wrapping.
  const auto signed_v = static_cast<std::int64_t>(v);
  const auto right = static_cast<std::uint64_t>(signed_v >> 55);
  return ((v << 8) ^ right) + static_cast<std::uint64_t>(static_cast<std::int64_t>(c));
}

std::uint64_t hash_string(std::uint64_t v, const std::string& s) {
  v = hash_update(v, static_cast<char>(s.size()));
  for (const char c : s) v = hash_update(v, c);
  return v;
}

// The base hash of a struct of primitive members (the struct's name is not part of it).
std::uint64_t base_hash(const std::vector<Member>& members) {
  std::uint64_t v = 0x12345678;
  for (const Member& m : members) {
    v = hash_string(v, m.name);
    v = hash_string(v, m.type);  // primitive types only (nested types hash recursively)
    v = hash_update(v, static_cast<char>(m.sizes.size()));
    for (const std::string& size : m.sizes) {
      v = hash_update(v, 0);  // LCM_CONST: a fixed size
      v = hash_string(v, size);
    }
  }
  return v;
}

// A type without nested types: the fingerprint is the base hash rotated left by one bit.
std::uint64_t fingerprint(std::uint64_t base) {
  return (base << 1) + ((base >> 63) & 1);
}

// libbot2's bot_core.pose_t, field for field.
std::vector<Member> libbot2_pose_members() {
  return {{"utime", "int64_t", {}},           {"pos", "double", {"3"}},
          {"vel", "double", {"3"}},           {"orientation", "double", {"4"}},
          {"rotation_rate", "double", {"3"}}, {"accel", "double", {"3"}}};
}

const char* const kLibbot2PoseDefinition = R"(package bot_core;
struct pose_t
{
    int64_t utime;
    double pos[3];
    double vel[3];
    double orientation[4];
    double rotation_rate[3];
    double accel[3];
}
)";

// Runs lcm-gen --cpp on an .lcm text and returns the base hash constant of the generated header.
std::uint64_t lcm_gen_base_hash(const std::string& definition, const std::string& name) {
  const auto dir = test::temp_dir("fingerprint_" + name);
  const auto lcm_file = dir / (name + ".lcm");
  std::ofstream(lcm_file) << definition;
  const int status = test::run_process(
      {LIVOD_LCM_GEN, "--cpp", "--cpp-hpath", (dir / "out").string(), lcm_file.string()},
      {.output = dir / "lcm-gen.txt"});
  EXPECT_EQ(status, 0) << test::read_text_file(dir / "lcm-gen.txt");
  const std::string header = test::read_text_file(dir / "out" / "bot_core" / "pose_t.hpp");
  // uint64_t hash = 0x170b...LL;  (no std::regex: GCC 12 warns inside it under ASan)
  const std::string marker = "hash = 0x";
  const std::size_t at = header.find(marker);
  const std::size_t end = at == std::string::npos ? at : header.find("LL", at);
  if (end == std::string::npos) {
    ADD_FAILURE() << "no hash constant in lcm-gen's output:\n" << header;
    return 0;
  }
  const std::size_t begin = at + marker.size();
  return std::stoull(header.substr(begin, end - begin), nullptr, 16);
}

TEST(LcmFingerprint, BotCorePoseEqualsLibbot2ByTheAlgorithm) {
  const std::uint64_t expected = fingerprint(base_hash(libbot2_pose_members()));
  EXPECT_EQ(::bot_core::pose_t::getHash(), expected)
      << std::hex << "generated 0x" << ::bot_core::pose_t::getHash() << ", libbot2 0x" << expected;
  // The value docs/lcm.md gives subscribers.
  EXPECT_EQ(expected, 0x2e16efb052b0105eULL);
}

TEST(LcmFingerprint, BotCorePoseEqualsWhatLcmGenComputesForLibbot2) {
  const std::uint64_t base = lcm_gen_base_hash(kLibbot2PoseDefinition, "libbot2");
  EXPECT_EQ(base, base_hash(libbot2_pose_members()));  // the algorithm above is LCM's
  EXPECT_EQ(::bot_core::pose_t::getHash(), fingerprint(base));
}

TEST(LcmFingerprint, TheChecksCanFail) {
  const std::uint64_t reference = fingerprint(base_hash(libbot2_pose_members()));
  // Reordered, renamed, retyped, resized: each gives another fingerprint.
  auto reordered = libbot2_pose_members();
  std::swap(reordered[1], reordered[2]);
  auto renamed = libbot2_pose_members();
  renamed[5].name = "acceleration";
  auto retyped = libbot2_pose_members();
  retyped[1].type = "float";
  auto resized = libbot2_pose_members();
  resized[3].sizes = {"3"};
  for (const auto& members : {reordered, renamed, retyped, resized}) {
    EXPECT_NE(fingerprint(base_hash(members)), reference);
  }
  // And lcm-gen agrees that a changed definition has another hash.
  std::string changed = kLibbot2PoseDefinition;
  changed.replace(changed.find("double accel[3]"), 15, "float accel[3]");
  EXPECT_NE(fingerprint(lcm_gen_base_hash(changed, "changed")), reference);
}

// The algorithm also reproduces a livod type (strings and a 2-D array included), so it is not
// tuned to one struct.
TEST(LcmFingerprint, AlgorithmReproducesLivodPose) {
  const std::vector<Member> members = {{"utime", "int64_t", {}},
                                       {"time_ns", "int64_t", {}},
                                       {"mapped_time_ns", "int64_t", {}},
                                       {"filter_time_ns", "int64_t", {}},
                                       {"sequence", "int64_t", {}},
                                       {"source", "int8_t", {}},
                                       {"status", "int8_t", {}},
                                       {"world_frame", "string", {}},
                                       {"body_frame", "string", {}},
                                       {"position", "double", {"3"}},
                                       {"orientation", "double", {"4"}},
                                       {"velocity", "double", {"3"}},
                                       {"angular_velocity", "double", {"3"}},
                                       {"acceleration", "double", {"3"}},
                                       {"covariance", "double", {"6", "6"}}};
  EXPECT_EQ(::livod::pose_t::getHash(), fingerprint(base_hash(members)));
}

// On the wire, a message starts with its fingerprint (big-endian): what subscribers and lcm-spy
// match on.
TEST(LcmFingerprint, EncodedMessagesStartWithTheFingerprint) {
  ::bot_core::pose_t m{};
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(m.getEncodedSize()));
  ASSERT_EQ(m.encode(bytes.data(), 0, static_cast<int>(bytes.size())),
            static_cast<int>(bytes.size()));
  std::uint64_t wire = 0;
  for (int i = 0; i < 8; ++i) wire = (wire << 8) | bytes[static_cast<std::size_t>(i)];
  EXPECT_EQ(wire, fingerprint(base_hash(libbot2_pose_members())));
  EXPECT_EQ(bytes.size(), 8u + 8u + 8u * 16u);  // fingerprint, utime, 16 doubles
}

}  // namespace
}  // namespace livod
