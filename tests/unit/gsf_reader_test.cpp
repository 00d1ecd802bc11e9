// The GSF reader on real files (NOAA Okeanos Explorer EM302 data, via UKHO gsfpy) and on damaged
// copies of them: every damage must end in a GsfError naming the record and byte offset.
#include "core/io/gsf/gsf_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <iterator>
#include <random>

#include "core/io/gsf/big_endian.h"
#include "core/io/gsf/gsf_survey.h"
#include "tests/unit/gsf_test_files.h"

namespace bathyslam::gsf {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using test::kEx1811;
using test::kGsfpy;
using test::pings_of;

std::string bytes_of(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path.string() + ": missing (set BATHYSLAM_GSF_DATA)");
  return {std::istreambuf_iterator<char>(in), {}};
}

std::vector<Record> read_all_records(std::string_view bytes) {
  MemorySource source(bytes);
  return test::records_of(source, "test.gsf");
}

// 2018-11-02 00:00:00 UTC and the day after.
constexpr double kNov2 = 1541116800.0;
constexpr double kNov3 = kNov2 + 86400.0;

TEST(GsfReader, Ex1811Em302ReadsAsFiftyPingsOf432Beams) {
  FileSource source(kEx1811);
  const FileSummary s = summarize_file(source, kEx1811.filename().string());
  EXPECT_EQ(s.version, "GSF-v03.07");
  EXPECT_EQ(s.bytes, fs::file_size(kEx1811));
  EXPECT_EQ(s.pings, 50u);
  EXPECT_EQ(s.ignored_pings, 0u);
  EXPECT_EQ(s.min_beams_per_ping, 432);
  EXPECT_EQ(s.max_beams_per_ping, 432);
  EXPECT_EQ(s.beams, 50u * 432u);
  EXPECT_EQ(s.soundings + s.rejected_beams, s.beams);
  EXPECT_GT(s.soundings, s.beams * 9 / 10);
  // The issue says 1170-2320 m; the shallowest usable beam (last ping, beam flags clear) is
  // 1165.56 m, the deepest 2316.67 m.
  EXPECT_NEAR(s.depth_min_m, 1165.56, 0.005);
  EXPECT_NEAR(s.depth_max_m, 2316.67, 0.005);
  EXPECT_NEAR(s.latitude_min, 17.84, 0.02);
  EXPECT_NEAR(s.latitude_max, 17.84, 0.02);
  EXPECT_NEAR(s.longitude_min, -64.60, 0.02);
  EXPECT_NEAR(s.longitude_max, -64.60, 0.02);
  EXPECT_GE(s.time_begin, kNov2);
  EXPECT_LT(s.time_end, kNov3);
  EXPECT_EQ(s.sound_velocity_profiles, 1u);
  EXPECT_EQ(s.processing_parameter_records, 1u);
  EXPECT_GT(s.attitude_records, 73000u);
  EXPECT_LT(s.attitude_records, 74500u);
}

TEST(GsfReader, Ex1811PingArraysAreScaledToMetresSecondsAndDegrees) {
  const std::vector<Ping> pings = pings_of(read_all_records(bytes_of(kEx1811)));
  ASSERT_EQ(pings.size(), 50u);
  for (const Ping& p : pings) {
    ASSERT_EQ(p.depth_m.size(), 432u);
    ASSERT_EQ(p.across_m.size(), 432u);
    ASSERT_EQ(p.along_m.size(), 432u);
    ASSERT_EQ(p.travel_time_s.size(), 432u);
    ASSERT_EQ(p.beam_angle_deg.size(), 432u);
    ASSERT_EQ(p.beam_flags.size(), 432u);
    EXPECT_GE(p.heading_deg, 0.0);
    EXPECT_LT(p.heading_deg, 360.0);
    // Port beams first: the outermost port beam is left of the keel, the starboard one right.
    EXPECT_LT(p.across_m.front(), -50.0);
    EXPECT_GT(p.across_m.back(), 50.0);
    for (std::size_t b = 0; b < 432; ++b) {
      if (p.beam_rejected(b)) continue;
      // An EM302's swath over 1.2-2.3 km of water is 4-5 km wide.
      EXPECT_LT(std::abs(p.across_m[b]), 3000.0);
      EXPECT_LT(std::abs(p.along_m[b]), 200.0);
      // The beam's geometry agrees with its two-way travel time at about 1500 m/s (the
      // depth is below the surface, the transducer a few metres down).
      const double range = std::hypot(p.across_m[b], p.along_m[b], p.depth_m[b]);
      EXPECT_NEAR(range / (0.5 * p.travel_time_s[b]), 1500.0, 40.0) << "beam " << b;
      EXPECT_LT(std::abs(p.beam_angle_deg[b]), 90.0);
    }
  }
  // Pings in time order, about every 6 s.
  for (std::size_t i = 1; i < pings.size(); ++i) EXPECT_GT(pings[i].time, pings[i - 1].time);
}

TEST(GsfReader, Ex1811MetadataRecordsAreDecoded) {
  const std::vector<Record> records = read_all_records(bytes_of(kEx1811));
  std::size_t profiles = 0, attitude_samples = 0;
  for (const Record& r : records) {
    if (const auto* svp = std::get_if<SoundVelocityProfile>(&r)) {
      ++profiles;
      ASSERT_GT(svp->depth_m.size(), 10u);
      for (double c : svp->sound_velocity_m_s) {
        EXPECT_GT(c, 1400.0);
        EXPECT_LT(c, 1700.0);  // Kongsberg profiles are extended to 12 km, where c is about 1675 m/s
      }
    }
    if (const auto* pp = std::get_if<ProcessingParameters>(&r)) {
      EXPECT_THAT(pp->parameters, ::testing::Contains(HasSubstr("REFERENCE TIME=")));
    }
    if (const auto* a = std::get_if<Attitude>(&r)) {
      attitude_samples += a->time.size();
      for (std::size_t i = 0; i < a->time.size(); ++i) {
        EXPECT_GE(a->time[i], kNov2);
        EXPECT_LT(std::abs(a->roll_deg[i]), 30.0);
        EXPECT_LT(std::abs(a->pitch_deg[i]), 30.0);
      }
    }
  }
  EXPECT_EQ(profiles, 1u);
  EXPECT_GT(attitude_samples, 73000u);
}

TEST(GsfReader, GsfpyTestDataReadsAsFourPingsOf432Beams) {
  FileSource source(kGsfpy);
  const FileSummary s = summarize_file(source, "gsfpy_test_data.gsf");
  EXPECT_EQ(s.pings, 4u);
  EXPECT_EQ(s.min_beams_per_ping, 432);
  EXPECT_EQ(s.max_beams_per_ping, 432);
  EXPECT_NEAR(s.latitude_min, 18.74, 0.02);
  EXPECT_NEAR(s.longitude_min, -67.62, 0.02);
  EXPECT_EQ(s.comments, 2u);
  EXPECT_EQ(s.skipped_records, 2u);  // a swath summary and a history record
  EXPECT_GT(s.soundings, 0u);
}

// --- damaged files ------------------------------------------------------------------------------

// Reading `bytes` must end in a GsfError whose message holds `expected`; returns the error.
GsfError expect_gsf_error(const std::string& bytes, const std::string& expected) {
  try {
    read_all_records(bytes);
  } catch (const GsfError& e) {
    EXPECT_THAT(e.what(), HasSubstr(expected));
    EXPECT_THAT(e.what(), HasSubstr("test.gsf: record "));
    return e;
  }
  ADD_FAILURE() << "no error; expected one with '" << expected << "'";
  return GsfError("", 0, 0, "");
}

void put_be32(std::string& bytes, std::size_t at, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) bytes[at + i] = static_cast<char>(v >> (24 - 8 * i));
}

TEST(GsfReaderDamage, TruncatedAnywhereInsideARecordNamesRecordAndOffset) {
  const std::string bytes = bytes_of(kGsfpy);
  // Inside the first framing, inside the first ping's data (record 7 at 4000), inside the last
  // record, and a few bytes into a record's framing.
  struct Cut {
    std::size_t at;
    std::uint64_t record, offset;
  };
  for (const Cut cut : {Cut{4, 1, 0}, Cut{5000, 7, 4000}, Cut{bytes.size() - 2, 45, 62248}, Cut{14252 + 6, 12, 14252}}) {
    const GsfError e = expect_gsf_error(bytes.substr(0, cut.at), "truncated");
    EXPECT_EQ(e.record(), cut.record) << "cut at " << cut.at;
    EXPECT_EQ(e.offset(), cut.offset) << "cut at " << cut.at;
  }
  // A cut on a record boundary is a shorter, valid file.
  EXPECT_EQ(pings_of(read_all_records(bytes.substr(0, 14252))).size(), 1u);
}

TEST(GsfReaderDamage, SizeRunningPastTheEndIsTruncationNotAnAllocation) {
  std::string bytes = bytes_of(kGsfpy);
  put_be32(bytes, 4000, 60u << 20);  // the first ping claims 60 MiB
  const GsfError e = expect_gsf_error(bytes, "declares 62914560 data bytes but the file ends");
  EXPECT_EQ(e.record(), 7u);
  EXPECT_EQ(e.offset(), 4000u);
}

TEST(GsfReaderDamage, FlippedSizeFieldsAreCaught) {
  const std::string original = bytes_of(kGsfpy);
  std::string bytes = original;
  put_be32(bytes, 4000, 0xffffff00u);
  expect_gsf_error(bytes, "exceeds the");
  bytes = original;
  put_be32(bytes, 4000, 6546);
  expect_gsf_error(bytes, "not a multiple of 4");
  // 4 bytes short: the ping's last subrecord no longer fits, then the next framing is garbage.
  bytes = original;
  put_be32(bytes, 4000, 6540);
  EXPECT_THROW(read_all_records(bytes), GsfError);
  // A subrecord size inside the ping that runs past the record.
  bytes = original;
  put_be32(bytes, 4008 + 56, (100u << 24) | 0xfffff0u);
  const GsfError e = expect_gsf_error(bytes, "runs past the end of the ping record");
  EXPECT_EQ(e.offset(), 4008u + 56u);
}

TEST(GsfReaderDamage, UnknownRecordIdAndImpossibleScaleFactorAreNamed) {
  const std::string original = bytes_of(kGsfpy);
  std::string bytes = original;
  put_be32(bytes, 4000 + 4, 99);  // registry 0, type 99
  expect_gsf_error(bytes, "unknown record id 99");
  // Private registries are skipped by size, as the specification says.
  bytes = original;
  put_be32(bytes, 68 + 4, (7u << 12) | 1u);
  EXPECT_EQ(pings_of(read_all_records(bytes)).size(), 4u);
  // Depth's multiplier (the first scale factor, after the 56-byte header, the subrecord word
  // and the count) set to 0.
  bytes = original;
  put_be32(bytes, 4008 + 56 + 4 + 4 + 4, 0);
  const GsfError e = expect_gsf_error(bytes, "depth array: impossible scale factor (multiplier 0)");
  EXPECT_EQ(e.record(), 7u);
}

TEST(GsfReaderDamage, NotGsfAtAll) {
  expect_gsf_error("", "empty file");
  expect_gsf_error("time,easting,northing,depth,roll,pitch,heading\n1,2,3,4,5,6,7\n", "not a GSF file");
  std::mt19937 random(17);
  std::string noise(4096, '\0');
  for (char& c : noise) c = static_cast<char>(random());
  expect_gsf_error(noise, "not a GSF file");
  // A GSF header followed by noise.
  expect_gsf_error(bytes_of(kGsfpy).substr(0, 20) + noise, "record 2 at byte 24: identifier");
}

// Random damage anywhere must end in a clean GsfError or a readable file, never anything else.
TEST(GsfReaderDamage, RandomByteFlipsNeverEscapeAsAnythingButGsfError) {
  const std::string original = bytes_of(kGsfpy);
  std::mt19937 random(3);
  int errors = 0;
  for (int trial = 0; trial < 300; ++trial) {
    std::string bytes = original;
    const int flips = 1 + static_cast<int>(random() % 8);
    for (int i = 0; i < flips; ++i) bytes[random() % bytes.size()] = static_cast<char>(random());
    try {
      read_all_records(bytes);
    } catch (const GsfError&) {
      ++errors;
    }
  }
  EXPECT_GT(errors, 0);
}

}  // namespace
}  // namespace bathyslam::gsf
