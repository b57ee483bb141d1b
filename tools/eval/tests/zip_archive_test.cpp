// The test-support ZIP/.npy reader: stored entries on evo's real result files, deflated entries
// on an archive assembled here with zlib, and clean errors on damaged input.

#include "tools/eval/tests/zip_archive.hpp"

#include <gtest/gtest.h>
#include <zlib.h>

#include <string>
#include <vector>

#include "tests/support/data_dir.hpp"

namespace livod::eval::test_support {
namespace {

void put16(std::string& s, unsigned v) {
  s.push_back(static_cast<char>(v & 0xff));
  s.push_back(static_cast<char>((v >> 8) & 0xff));
}

void put32(std::string& s, unsigned long v) {
  put16(s, static_cast<unsigned>(v & 0xffff));
  put16(s, static_cast<unsigned>((v >> 16) & 0xffff));
}

std::string raw_deflate(const std::string& data) {
  z_stream z{};
  EXPECT_EQ(deflateInit2(&z, 9, Z_DEFLATED, -MAX_WBITS, 8, Z_DEFAULT_STRATEGY), Z_OK);
  std::string out(deflateBound(&z, static_cast<uLong>(data.size())), '\0');
  z.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
  z.avail_in = static_cast<uInt>(data.size());
  z.next_out = reinterpret_cast<Bytef*>(out.data());
  z.avail_out = static_cast<uInt>(out.size());
  EXPECT_EQ(deflate(&z, Z_FINISH), Z_STREAM_END);
  out.resize(z.total_out);
  deflateEnd(&z);
  return out;
}

// A one-entry archive (APPNOTE 4.3.7 local header, 4.3.12 central header, 4.3.16 end record).
std::string make_zip(const std::string& name, const std::string& data, bool deflated) {
  const std::string payload = deflated ? raw_deflate(data) : data;
  const unsigned long crc =
      crc32(0L, reinterpret_cast<const Bytef*>(data.data()), static_cast<uInt>(data.size()));
  const unsigned method = deflated ? 8 : 0;
  std::string zip;
  put32(zip, 0x04034b50);
  put16(zip, 20);
  put16(zip, 0);
  put16(zip, method);
  put16(zip, 0);
  put16(zip, 0);
  put32(zip, crc);
  put32(zip, payload.size());
  put32(zip, data.size());
  put16(zip, static_cast<unsigned>(name.size()));
  put16(zip, 0);
  zip += name;
  zip += payload;
  const std::size_t cd_offset = zip.size();
  put32(zip, 0x02014b50);
  put16(zip, 20);
  put16(zip, 20);
  put16(zip, 0);
  put16(zip, method);
  put16(zip, 0);
  put16(zip, 0);
  put32(zip, crc);
  put32(zip, payload.size());
  put32(zip, data.size());
  put16(zip, static_cast<unsigned>(name.size()));
  put16(zip, 0);
  put16(zip, 0);
  put16(zip, 0);
  put16(zip, 0);
  put32(zip, 0);
  put32(zip, 0);  // local header at offset 0
  zip += name;
  const std::size_t cd_size = zip.size() - cd_offset;
  put32(zip, 0x06054b50);
  put16(zip, 0);
  put16(zip, 0);
  put16(zip, 1);
  put16(zip, 1);
  put32(zip, cd_size);
  put32(zip, cd_offset);
  put16(zip, 0);
  return zip;
}

TEST(ZipArchive, ReadsEvoResultFiles) {
  const ZipArchive zip =
      ZipArchive::open(livod::test::data_path("trajectory_eval/res_files/orb_rpe.zip"));
  EXPECT_TRUE(zip.contains("info.json"));
  EXPECT_TRUE(zip.contains("stats.json"));
  EXPECT_EQ(zip.read("info.json").front(), '{');
  const std::vector<double> errors = parse_npy_f8(zip.read("error_array.npz"), "error_array");
  EXPECT_GT(errors.size(), 100u);
  for (double e : errors) ASSERT_GE(e, 0.0);
  EXPECT_THROW(static_cast<void>(zip.read("missing.json")), Error);
}

TEST(ZipArchive, InflatesDeflatedEntries) {
  std::string text;
  for (int i = 0; i < 500; ++i) text += "line " + std::to_string(i) + " of a compressible text\n";
  const std::string zip = make_zip("a.txt", text, true);
  ASSERT_LT(zip.size(), text.size());  // really compressed
  EXPECT_EQ(ZipArchive(zip, "mem").read("a.txt"), text);
  EXPECT_EQ(ZipArchive(make_zip("b.txt", text, false), "mem").read("b.txt"), text);
}

TEST(ZipArchive, DamagedArchivesFailCleanly) {
  const std::string text(1000, 'x');
  std::string corrupt = make_zip("a.txt", text, false);
  corrupt[40] = 'y';  // inside the stored data: CRC mismatch
  EXPECT_THROW(static_cast<void>(ZipArchive(corrupt, "mem").read("a.txt")), FormatError);
  const std::string good = make_zip("a.txt", text, true);
  for (std::size_t cut : {std::size_t{0}, std::size_t{10}, good.size() / 2, good.size() - 1}) {
    EXPECT_THROW(ZipArchive(good.substr(0, cut), "mem"), FormatError) << cut;
  }
  std::string bad_deflate = good;
  bad_deflate[40] = static_cast<char>(~bad_deflate[40]);
  EXPECT_THROW(static_cast<void>(ZipArchive(bad_deflate, "mem").read("a.txt")), FormatError);
}

TEST(Npy, RejectsWhatItCannotRead) {
  EXPECT_THROW(parse_npy_f8("not numpy", "x"), FormatError);
  std::string header = "{'descr': '<f4', 'fortran_order': False, 'shape': (1,), }";
  std::string npy = std::string("\x93NUMPY\x01\x00", 8);
  put16(npy, static_cast<unsigned>(header.size()));
  EXPECT_THROW(parse_npy_f8(npy + header + "abcd", "x"), FormatError);
  header = "{'descr': '<f8', 'fortran_order': False, 'shape': (2,), }";
  npy = std::string("\x93NUMPY\x01\x00", 8);
  put16(npy, static_cast<unsigned>(header.size()));
  EXPECT_THROW(parse_npy_f8(npy + header + std::string(8, '\0'), "x"), FormatError);  // short
  const std::vector<double> two = parse_npy_f8(npy + header + std::string(16, '\0'), "x");
  EXPECT_EQ(two, (std::vector<double>{0.0, 0.0}));
}

}  // namespace
}  // namespace livod::eval::test_support
