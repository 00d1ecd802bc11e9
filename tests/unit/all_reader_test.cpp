// Kongsberg EM .all in: the datagram reader on real files and on damaged bytes, and the survey
// made of the files (soundings where the sonar put them, swaths outside the fixes left out).
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/io/crs.h"
#include "core/io/kongsberg/all_datagrams.h"
#include "core/io/kongsberg/all_survey.h"
#include "core/io/survey_input.h"
#include "core/types/pose.h"

namespace bathyslam::kongsberg {
namespace {

const std::filesystem::path kData = BATHYSLAM_ALL_DATA;
const std::filesystem::path kEm2040 = kData / "0077_20221109_123655_Belgica.all";
const std::filesystem::path kEm122 = kData / "0243_P007_MBES_EM122_20150207_044356_Supporter_GA4430.all";

std::string bytes_of(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::vector<Datagram> read_all_datagrams(const std::string& bytes) {
  MemorySource source(bytes);
  Reader reader(source, "x.all");
  std::vector<Datagram> out;
  while (auto d = reader.next()) out.push_back(std::move(*d));
  return out;
}

// One datagram framed as an EM sonar frames it: length, STX, type, header, body, ETX, checksum.
std::string datagram(char type, const std::string& body, std::uint32_t date = 20240131, std::uint32_t ms = 3'600'000) {
  std::string d;
  d += '\x02';
  d += type;
  auto put = [&](std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) d += static_cast<char>((v >> (8 * i)) & 0xff);
  };
  put(2040, 2);
  put(date, 4);
  put(ms, 4);
  put(1, 2);
  put(100, 2);
  d += body;
  d += '\x03';
  std::uint16_t sum = 0;
  for (std::size_t i = 1; i + 1 < d.size(); ++i) sum = static_cast<std::uint16_t>(sum + static_cast<unsigned char>(d[i]));
  put(sum, 2);
  std::string framed;
  const auto n = static_cast<std::uint32_t>(d.size());
  for (int i = 0; i < 4; ++i) framed += static_cast<char>((n >> (8 * i)) & 0xff);
  return framed + d;
}

std::string le(std::uint64_t v, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += static_cast<char>((v >> (8 * i)) & 0xff);
  return s;
}
std::string f32(float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  return le(bits, 4);
}

// An XYZ 88 body of `beams` beams claimed and `written` written, each 10 m deep and 2 m to starboard.
std::string xyz88_body(std::uint16_t beams, std::uint16_t written, std::uint8_t detection = 0) {
  std::string b = le(9000, 2) + le(15000, 2) + f32(2.0f) + le(beams, 2) + le(beams, 2) + f32(30000.0f) + std::string(4, '\0');
  for (std::uint16_t i = 0; i < written; ++i) {
    b += f32(10.0f) + f32(2.0f) + f32(0.5f) + le(0, 2) + le(0, 1) + le(0, 1) + le(detection, 1) + le(0, 1) + le(0, 2);
  }
  return b + std::string(1, '\0');  // spare
}

TEST(AllReader, DecodesTheDatagramsOfARealDualHeadEm2040File) {
  const std::vector<Datagram> all = read_all_datagrams(bytes_of(kEm2040));
  ASSERT_EQ(all.size(), 141u);
  int swaths = 0, fixes = 0, attitude = 0, installation = 0;
  const SoundSpeedProfile* profile = nullptr;
  const DepthPing* first = nullptr;
  for (const Datagram& d : all) {
    if (const auto* p = std::get_if<DepthPing>(&d)) {
      ++swaths;
      if (!first) first = p;
    }
    fixes += std::holds_alternative<Position>(d);
    attitude += std::holds_alternative<Attitude>(d);
    installation += std::holds_alternative<Installation>(d);
    if (const auto* p = std::get_if<SoundSpeedProfile>(&d)) profile = p;
  }
  ASSERT_NE(profile, nullptr);  // 16 points, 1498.0 m/s at the surface, 1669.0 m/s at 12,000 m
  ASSERT_EQ(profile->depth_m.size(), 16u);
  EXPECT_DOUBLE_EQ(profile->sound_speed_m_s.front(), 1498.0);
  EXPECT_DOUBLE_EQ(profile->depth_m.back(), 12000.0);
  EXPECT_DOUBLE_EQ(profile->sound_speed_m_s.back(), 1669.0);
  EXPECT_EQ(swaths, 9);
  EXPECT_EQ(fixes, 8);
  EXPECT_EQ(attitude, 8);
  EXPECT_EQ(installation, 1);
  ASSERT_NE(first, nullptr);
  EXPECT_EQ(first->serial, 2004);
  EXPECT_EQ(first->beams.size(), 256u);
  EXPECT_NEAR(first->heading_deg, 311.58, 1e-9);
  EXPECT_NEAR(first->transducer_depth_m, 5.5, 0.01);
  // 2022-11-09 12:36:54.649 UTC, from the datagram's date and milliseconds since midnight.
  EXPECT_NEAR(first->time, 1667997414.649, 1e-6);
  EXPECT_TRUE(first->beams[128].valid());
  EXPECT_NEAR(first->beams[128].depth_m, 9.65, 0.15);  // ~15 m of water below a 5.5 m transducer
}

TEST(AllReader, ActivePositionFixesAreFlaggedAndOnTheEarth) {
  int active = 0;
  for (const Datagram& d : read_all_datagrams(bytes_of(kEm2040))) {
    const auto* p = std::get_if<Position>(&d);
    if (!p) continue;
    active += p->active;
    EXPECT_NEAR(p->latitude_deg, 51.3685, 1e-3);  // off Zeebrugge
    EXPECT_NEAR(p->longitude_deg, 3.1393, 1e-3);
  }
  EXPECT_EQ(active, 4);  // system 1 (descriptor 0xC1); system 3 (0x03) is not used in real time
}

TEST(AllReader, DamageIsAnErrorNamingFileOffsetAndField) {
  const std::string good = datagram('X', xyz88_body(2, 2));
  const auto error_of = [](const std::string& bytes) -> std::string {
    try {
      read_all_datagrams(bytes);
    } catch (const AllError& e) {
      return e.what();
    }
    return "no error";
  };
  EXPECT_EQ(read_all_datagrams(good + good).size(), 2u);
  // Truncated inside the second datagram: its offset, its length field.
  EXPECT_THAT(error_of(good + good.substr(0, good.size() - 5)),
              testing::StartsWith("x.all:" + std::to_string(good.size()) + ": datagram length: "));
  EXPECT_THAT(error_of(good.substr(0, 2)), testing::HasSubstr("x.all:0: datagram length: the file ends inside it"));
  // A length that lies past the end of the file.
  std::string lying = good;
  lying[2] = '\x7f';
  EXPECT_THAT(error_of(lying), testing::HasSubstr("run past the end of the file"));
  std::string huge = good;
  huge[3] = '\x7f';
  EXPECT_THAT(error_of(huge), testing::HasSubstr("over the"));
  const std::string five_byte_datagram = le(5, 4) + "\x02" + "abcd";  // a length under the 19-byte frame
  EXPECT_THAT(error_of(five_byte_datagram), testing::HasSubstr("x.all:0: datagram length: 5 bytes is shorter than a datagram's frame"));
  // One byte of the body changed: the checksum no longer adds up.
  std::string flipped = good;
  flipped[40] ^= 0x10;
  EXPECT_THAT(error_of(flipped), testing::HasSubstr("x.all:0: checksum: "));
  // More beams claimed than written.
  EXPECT_THAT(error_of(datagram('X', xyz88_body(5, 2))), testing::HasSubstr("x.all:0: 'X' datagram beam depth: runs past the end"));
  EXPECT_THAT(error_of(datagram('P', le(0, 4) + le(0, 4))), testing::HasSubstr("'P' datagram fix quality"));
  EXPECT_THAT(error_of(datagram('P', le(0x7fffffff, 4) + std::string(14, '\0'))), testing::HasSubstr("'P' datagram latitude"));
  EXPECT_THAT(error_of(datagram('X', xyz88_body(2, 2), 20241341)), testing::HasSubstr("date: 20241341 is not a YYYYMMDD date"));
  std::string no_stx = good;
  no_stx[4] = 'Z';
  EXPECT_THAT(error_of(no_stx), testing::HasSubstr("STX"));
}

TEST(AllReader, UnknownDatagramsAreSkippedAndInvalidDetectionsRejected) {
  const std::vector<Datagram> all =
      read_all_datagrams(datagram('k', std::string(100, '\x55')) + datagram('X', xyz88_body(3, 3, 0x80)) +
                         datagram('X', xyz88_body(0, 0)));
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(std::get<Skipped>(all[0]).type, 'k');
  for (const DepthBeam& b : std::get<DepthPing>(all[1]).beams) EXPECT_FALSE(b.valid());
  EXPECT_TRUE(std::get<DepthPing>(all[2]).beams.empty());
}

// Where a sounding lands, computed straight from the datagrams: the fix interpolated at the
// ping, the beam's along/across turned by the swath's heading, its depth below the transducer.
TEST(AllSurvey, SoundingsLandWhereTheSonarPutThem) {
  const SurveyRead read = read_survey({kEm122});
  const Survey& s = read.survey;
  ASSERT_EQ(read.files.size(), 1u);
  EXPECT_EQ(read.files[0].swaths, 11u);
  EXPECT_EQ(read.files[0].swaths_outside_navigation, 2u);  // two pings before the first fix
  ASSERT_EQ(s.pings.size(), 9u);
  EXPECT_EQ(s.metadata.crs, "EPSG:32745");  // UTM 45 S

  std::vector<Position> fixes;
  std::vector<DepthPing> swaths;
  for (Datagram& d : read_all_datagrams(bytes_of(kEm122))) {
    if (auto* p = std::get_if<Position>(&d); p && p->active) fixes.push_back(*p);
    if (auto* p = std::get_if<DepthPing>(&d)) swaths.push_back(std::move(*p));
  }
  const GeographicProjection projection(s.metadata.crs);
  const LocalOrigin origin{};
  int checked = 0;
  for (const Ping& ping : s.pings) {
    const auto swath = std::find_if(swaths.begin(), swaths.end(), [&](const DepthPing& d) { return d.time == ping.time; });
    ASSERT_NE(swath, swaths.end());
    const auto after = std::find_if(fixes.begin(), fixes.end(), [&](const Position& f) { return f.time >= ping.time; });
    ASSERT_NE(after, fixes.end());
    ASSERT_NE(after, fixes.begin());
    const Position& a = *(after - 1);
    const double w = (ping.time - a.time) / (after->time - a.time);
    const auto fix = projection.forward(a.longitude_deg + w * (after->longitude_deg - a.longitude_deg),
                                        a.latitude_deg + w * (after->latitude_deg - a.latitude_deg));
    const NavSample nav = *std::find_if(s.nav.begin(), s.nav.end(), [&](const NavSample& n) { return n.time == ping.time; });
    const Eigen::Isometry3d pose = vehicle_pose(nav, origin);
    for (const Beam& b : s.beams_of(ping)) {
      const DepthBeam& raw = swath->beams[b.index];
      const double h = swath->heading_deg * M_PI / 180.0;
      const Eigen::Vector3d expected(fix.easting + raw.along_m * std::sin(h) + raw.across_m * std::cos(h),
                                     fix.northing + raw.along_m * std::cos(h) - raw.across_m * std::sin(h),
                                     -(raw.depth_m + swath->transducer_depth_m));
      const Eigen::Vector3d landed = pose * Eigen::Vector3d(b.along, b.across, b.down);
      ASSERT_LT((landed - expected).norm(), 0.01) << "ping " << ping.time << " beam " << b.index;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 3886);
}

TEST(AllSurvey, StreamedSoundingsAreTheSoundingsReadWhole) {
  struct Collect : PingSink {
    std::vector<Beam> beams;
    std::vector<double> times;
    void begin(const Survey&) override {}
    void ping(double time, std::span<const Beam> b) override {
      times.push_back(time);
      beams.insert(beams.end(), b.begin(), b.end());
    }
  } sink;
  const SurveyRead whole = read_survey({kEm2040});
  SurveyRead outline = read_survey({kEm2040}, {"", std::nullopt, false});
  EXPECT_TRUE(outline.survey.beams.empty());
  stream_soundings({kEm2040}, outline.survey, sink);
  ASSERT_EQ(sink.beams.size(), whole.survey.beams.size());
  ASSERT_EQ(sink.times.size(), whole.survey.pings.size());
  // Both heads of one ping cycle, in time order although the file interleaves them.
  EXPECT_TRUE(std::is_sorted(sink.times.begin(), sink.times.end()));
  for (std::size_t i = 0; i < sink.beams.size(); ++i) {
    ASSERT_EQ(sink.beams[i].down, whole.survey.beams[i].down);
    ASSERT_EQ(sink.beams[i].across, whole.survey.beams[i].across);
  }
}

TEST(AllSurvey, FilesOfUnknownOrderAreOrderedByTheirFirstSwathAndFormatsAreNotMixed) {
  EXPECT_EQ(sonar_files_in_time_order({kEm2040, kEm122}), (std::vector<std::filesystem::path>{kEm122, kEm2040}));
  try {
    sonar_files_in_time_order({kEm2040, kData / "x.gsf"});
    FAIL() << "a .gsf and an .all file were taken as one survey";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("must be of one format"));
  }
}

TEST(AllSurvey, AFileWithoutUsableSwathsIsRefusedByName) {
  const std::filesystem::path path = std::filesystem::temp_directory_path() / "bathyslam_no_fix.all";
  {
    std::ofstream out(path, std::ios::binary);
    const std::string x = datagram('X', xyz88_body(2, 2));
    out.write(x.data(), static_cast<std::streamsize>(x.size()));
  }
  try {
    read_survey({path});
    FAIL() << "a swath without any position fix made a survey";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr(path.string() + ": no swath with soundings within the position fixes"));
  }
  std::filesystem::remove(path);
}

}  // namespace
}  // namespace bathyslam::kongsberg
