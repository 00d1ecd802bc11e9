// XTF in: the packet reader on a real R2Sonic file logged by QINSy and on damaged bytes, and the
// survey made of it (attitude applied in the sense that levels the swath, navigation from the
// ping headers when a file has no navigation packets).
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core/io/survey_input.h"
#include "core/io/xtf/xtf_packets.h"
#include "core/io/xtf/xtf_survey.h"
#include "core/types/pose.h"

namespace bathyslam::xtf {
namespace {

const std::filesystem::path kFile = std::filesystem::path(BATHYSLAM_XTF_DATA) / "0009_150708_R2Testing_0001.xtf";

// Where the file's first packets are (its layout, read with a hex viewer): a position packet at
// 1024, an attitude packet at 1088, the first bathymetry packet at 1152 with its BTH0 packet at
// 1408 and its sections H0 at 1420, R0 at 1536, A2 at 2056, I1 at 2604, G0 at 3124, Q0 at 3140.
constexpr std::size_t kFirstPing = 1152, kH0 = 1420, kR0 = 1536, kQ0 = 3140;

std::string bytes_of(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

std::vector<Packet> packets_of(const std::string& bytes) {
  MemorySource source(bytes);
  Reader reader(source, "x.xtf");
  std::vector<Packet> out;
  while (auto p = reader.next()) out.push_back(std::move(*p));
  return out;
}

std::string error_of(const std::string& bytes) {
  try {
    packets_of(bytes);
  } catch (const XtfError& e) {
    return e.what();
  }
  return "no error";
}

void put_be16(std::string& b, std::size_t at, std::uint16_t v) {
  b[at] = static_cast<char>(v >> 8);
  b[at + 1] = static_cast<char>(v & 0xff);
}

TEST(XtfReader, DecodesTheR2SonicFileOfQinsy) {
  const std::string bytes = bytes_of(kFile);
  MemorySource source(bytes);
  Reader reader(source, "x.xtf");
  const FileHeader& h = reader.header();
  EXPECT_EQ(h.recording_program, "QINSy");
  EXPECT_EQ(h.navigation_units, 3);
  EXPECT_EQ(h.bathymetry_channels, 1);
  ASSERT_TRUE(h.bathymetry);
  EXPECT_NEAR(h.bathymetry->starboard_m, 5.341, 1e-5);
  EXPECT_NEAR(h.bathymetry->forward_m, 1.219, 1e-5);
  EXPECT_NEAR(h.bathymetry->down_m, 3.38, 1e-5);
  EXPECT_NEAR(h.bathymetry->roll_deg, 1.77, 1e-5);

  std::map<int, int> counts;
  std::optional<BathyPing> first;
  std::optional<Position> first_fix;
  std::optional<Attitude> first_attitude;
  while (auto p = reader.next()) {
    if (auto* ping = std::get_if<BathyPing>(&*p)) {
      ++counts[kR2SonicBathymetry];
      if (!first) first = std::move(*ping);
    } else if (const auto* fix = std::get_if<Position>(&*p)) {
      ++counts[kPosition];
      if (!first_fix) first_fix = *fix;
    } else if (const auto* a = std::get_if<Attitude>(&*p)) {
      ++counts[kAttitude];
      if (!first_attitude) first_attitude = *a;
    } else {
      ++counts[0];
    }
  }
  EXPECT_EQ(counts, (std::map<int, int>{{kAttitude, 1203}, {kR2SonicBathymetry, 923}, {kPosition, 1204}}));
  EXPECT_EQ(reader.bytes_read(), bytes.size());
  // 2015-07-08 23:52:15.908 UTC, 37.75685 N 122.37745 W.
  EXPECT_NEAR(first_fix->time, 1436399535.908, 1e-6);
  EXPECT_NEAR(first_fix->latitude_deg, 37.756849828, 1e-8);
  EXPECT_NEAR(first_fix->longitude_deg, -122.377451444, 1e-8);
  EXPECT_NEAR(first_attitude->time, 1436399535.908, 1e-6);
  EXPECT_NEAR(first_attitude->heading_deg, 250.880, 1e-3);
  EXPECT_NEAR(first_attitude->roll_deg, 0.2171, 1e-4);
  EXPECT_NEAR(first_attitude->pitch_deg, -0.7049, 1e-4);

  EXPECT_EQ(first->model, "2026");
  EXPECT_EQ(first->ping_number, 151989u);
  EXPECT_NEAR(first->time, 1436399535.920431109, 1e-6);
  EXPECT_NEAR(first->sound_speed_m_s, 1514.962, 1e-3);
  ASSERT_EQ(first->beams.size(), 256u);
  // Beam 0: 8069 counts of 3.8297e-6 s, at -1.07409 rad (A2's first angle, its first step 0).
  EXPECT_NEAR(first->beams[0].two_way_time_s, 8069 * 3.829656634e-6, 1e-9);
  EXPECT_NEAR(first->beams[0].angle_rad, -1.0740883, 1e-6);
  EXPECT_NEAR(first->beams[255].angle_rad, 1.0817, 1e-3);
  // Q0: beams off nadir detected by phase, near nadir by magnitude, both tests passed.
  EXPECT_EQ(first->beams[0].quality, 0xB);
  EXPECT_EQ(first->beams[127].quality, 0x7);
  EXPECT_TRUE(first->beams[0].valid() && first->beams[127].valid());
  EXPECT_TRUE(first->header.position_usable() && first->header.attitude_usable());
}

TEST(XtfReader, DamageIsAnErrorNamingFileOffsetAndField) {
  const std::string good = bytes_of(kFile);
  std::string b = good;
  b[0] = 7;
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:0: file header FileFormat: 7 is not 123"));
  b = good.substr(0, 600);
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:0: file header: the file ends after 600 of its 1024 bytes"));
  b = good;
  b[1024] = 0;
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1024: packet magic number: 0xFA00 is not 0xFACE"));
  b = good.substr(0, kFirstPing + 1000);  // the first ping cut short
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1152: NumBytesThisRecord: 2176 bytes run past the end of the file"));
  b = good;
  b[kFirstPing + 13] = 0x7f;  // a length of about 2 GiB
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1152: NumBytesThisRecord: 2130708608 bytes is over the"));
  b = good;
  put_be16(b, kH0 + 2, 0);  // a section of no size would never end
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1152: R2Sonic bathymetry packet section size: 0 bytes do not fit"));
  b = good;
  put_be16(b, kH0 + 114, 4000);  // more points than R0 holds
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1152: R2Sonic bathymetry packet R0 range: runs past the end"));
  b = good;
  std::memset(&b[kH0 + 44], 0, 4);  // no sound speed
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1152: R2Sonic bathymetry packet H0 sound speed: 0.000000 m/s is not"));
  b = good;
  b[1024 + 14 + 2] = 13;  // the first fix in month 13 (after the packet header and the year)
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1024: position packet date: 2015-13-8 is not a date"));
  b = good;
  const double off_the_earth = 95.0;
  std::memcpy(&b[1024 + 14 + 9], &off_the_earth, 8);  // the first fix's latitude
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1024: position packet RawYcoordinate: 95.000000 is out of range"));
  b = good;
  put_be16(b, kR0 + 4, 0x7e00);  // a range scale of about 4e37 s a count
  EXPECT_THAT(error_of(b), testing::HasSubstr("x.xtf:1152: R2Sonic bathymetry packet R0 scaling factor:"));
}

TEST(XtfReader, UnknownPacketsAreSkippedAndBeamsWithoutDetectionRejected) {
  std::string b = bytes_of(kFile);
  b[1088 + 2] = static_cast<char>(200);  // the first attitude packet becomes a user-defined one
  std::memset(&b[kQ0 + 4], 0, 4);        // the first eight beams: no test passed, no detection
  const std::vector<Packet> packets = packets_of(b);
  ASSERT_TRUE(std::holds_alternative<Skipped>(packets[1]));
  EXPECT_EQ(std::get<Skipped>(packets[1]).type, 200);
  const auto& ping = std::get<BathyPing>(packets[2]);
  for (int i = 0; i < 8; ++i) EXPECT_FALSE(ping.beams[i].valid()) << i;
  EXPECT_TRUE(ping.beams[8].valid());
}

// The across-track slope of each ping's soundings in a level frame (depth on across distance).
std::vector<double> swath_slopes(const Survey& s) {
  std::vector<double> slopes;
  for (const Ping& p : s.pings) {
    const NavSample* nav = nullptr;
    for (const NavSample& n : s.nav) {
      if (n.time == p.time) nav = &n;
    }
    const Eigen::Matrix3d level = vehicle_to_level_rotation(nav->roll_deg, nav->pitch_deg);
    double sy = 0, sz = 0, syy = 0, syz = 0;
    for (std::uint32_t k = 0; k < p.beam_count; ++k) {
      const Beam& b = s.beams[p.first_beam + k];
      const Eigen::Vector3d v = level * Eigen::Vector3d(b.along, b.across, b.down);
      sy += v.y(), sz += v.z(), syy += v.y() * v.y(), syz += v.y() * v.z();
    }
    const double n = p.beam_count;
    slopes.push_back((syz - sy * sz / n) / (syy - sy * sy / n));
  }
  return slopes;
}

double spread(const std::vector<double>& v) {
  double m = 0, q = 0;
  for (double x : v) m += x / v.size();
  for (double x : v) q += (x - m) * (x - m) / v.size();
  return std::sqrt(q);
}

// The sonar's angles are across the array, not stabilised: the vessel's roll must be applied in
// the sense that turns each ping's seabed the same way (a flat bay). Applied the wrong way round,
// or not at all, the ping-to-ping spread of the across-track slope grows tenfold.
TEST(XtfSurvey, AttitudeLevelsEverySwathAndDepthsAreTheBays) {
  const SurveyRead read = read_survey({kFile});
  const Survey& s = read.survey;
  EXPECT_EQ(s.metadata.crs, "EPSG:32610");
  EXPECT_EQ(s.pings.size(), 923u);
  EXPECT_EQ(s.beams.size(), 236288u);
  EXPECT_LT(spread(swath_slopes(s)), 0.01);

  Survey unrolled = s;
  for (NavSample& n : unrolled.nav) n.roll_deg = -n.roll_deg;
  EXPECT_GT(spread(swath_slopes(unrolled)), 0.03);

  std::vector<float> depth;
  for (const Beam& b : s.beams) depth.push_back(b.down);
  std::nth_element(depth.begin(), depth.begin() + depth.size() / 2, depth.end());
  EXPECT_NEAR(depth[depth.size() / 2], 13.8, 0.2);  // below the reference point at the water line
  EXPECT_EQ(read.files[0].soundings, 236288u);
}

TEST(XtfSurvey, StreamedSoundingsAreTheSoundingsReadWhole) {
  const Survey whole = read_survey({kFile}).survey;
  Survey navigation = read_survey({kFile}, {"", std::nullopt, false}).survey;
  struct Collect : PingSink {
    std::vector<Beam> beams;
    void begin(const Survey&) override {}
    void ping(double, std::span<const Beam> b) override { beams.insert(beams.end(), b.begin(), b.end()); }
  } sink;
  stream_soundings({kFile}, navigation, sink);
  ASSERT_EQ(sink.beams.size(), whole.beams.size());
  for (std::size_t i = 0; i < whole.beams.size(); i += 997) {
    EXPECT_EQ(sink.beams[i].across, whole.beams[i].across);
    EXPECT_EQ(sink.beams[i].down, whole.beams[i].down);
  }
}

// A file without position and attitude packets: the navigation the logger wrote into each ping
// header (QINSy writes its latest fix and attitude there) takes their place.
TEST(XtfSurvey, WithoutNavigationPacketsThePingHeadersNavigate) {
  std::string b = bytes_of(kFile);
  for (std::size_t at = 1024; at < b.size();) {
    std::uint32_t n = 0;
    for (int i = 3; i >= 0; --i) n = (n << 8) | static_cast<unsigned char>(b[at + 10 + i]);
    if (b[at + 2] == static_cast<char>(kPosition) || b[at + 2] == static_cast<char>(kAttitude)) b[at + 2] = static_cast<char>(200);
    at += n;
  }
  const std::filesystem::path stripped = std::filesystem::temp_directory_path() / "xtf_test_stripped.xtf";
  std::ofstream(stripped, std::ios::binary) << b;
  const SurveyRead from_headers = read_survey({stripped});
  const SurveyRead from_packets = read_survey({kFile});
  std::filesystem::remove(stripped);
  EXPECT_TRUE(from_headers.files[0].navigation_from_ping_headers);
  // One fix per ping header that carries a newer one than the last (NavFixMilliseconds).
  EXPECT_GT(from_headers.files[0].positions, 700u);
  EXPECT_LE(from_headers.files[0].positions, 923u);
  const auto& a = from_packets.survey.nav;
  const auto& h = from_headers.survey.nav;
  ASSERT_GT(h.size(), 900u);
  // The last ping may fall after the last header fix: compare the samples both have.
  for (std::size_t i = 0, j = 0; i < h.size() && j < a.size(); ++i) {
    while (j < a.size() && a[j].time < h[i].time) ++j;
    if (j == a.size() || a[j].time != h[i].time) continue;
    EXPECT_NEAR(h[i].easting, a[j].easting, 0.3) << i;
    EXPECT_NEAR(h[i].northing, a[j].northing, 0.3) << i;
    EXPECT_NEAR(h[i].heading_deg, a[j].heading_deg, 1.0) << i;
    EXPECT_NEAR(h[i].roll_deg, a[j].roll_deg, 1.0) << i;
  }
}

// The motion sensor silent for five seconds: the pings then have no roll or heading of their own
// and are counted out, not georeferenced with the last sample's.
TEST(XtfSurvey, PingsInAnAttitudeDropoutAreCountedNotKept) {
  std::string b = bytes_of(kFile);
  int silenced = 0;
  for (std::size_t at = 1024; at < b.size();) {
    std::uint32_t n = 0;
    for (int i = 3; i >= 0; --i) n = (n << 8) | static_cast<unsigned char>(b[at + 10 + i]);
    if (b[at + 2] == static_cast<char>(kAttitude)) {
      const int second = static_cast<unsigned char>(b[at + 14 + 40 + 6]);  // the sample's second of the minute
      if (second >= 30 && second < 35) b[at + 2] = static_cast<char>(200), ++silenced;
    }
    at += n;
  }
  ASSERT_GT(silenced, 100);
  const std::filesystem::path gap = std::filesystem::temp_directory_path() / "xtf_test_attitude_gap.xtf";
  std::ofstream(gap, std::ios::binary) << b;
  const SurveyRead read = read_survey({gap});
  Survey outline = read_survey({gap}, {"", std::nullopt, false}).survey;
  struct Count : PingSink {
    std::size_t pings = 0;
    void begin(const Survey&) override {}
    void ping(double, std::span<const Beam>) override { ++pings; }
  } sink;
  stream_soundings({gap}, outline, sink);
  std::filesystem::remove(gap);
  // About 5 s of pings at 19 a second, less the second at either edge still within reach.
  EXPECT_GT(read.files[0].pings_outside_navigation, 50u);
  EXPECT_LT(read.files[0].pings_outside_navigation, 100u);
  EXPECT_EQ(read.survey.pings.size() + read.files[0].pings_outside_navigation, 923u);
  EXPECT_EQ(sink.pings, read.survey.pings.size()) << "the streamed reading leaves the same pings out";
}

TEST(XtfSurvey, FilesOfOneFormatOnlyAndInTimeOrder) {
  EXPECT_TRUE(is_sonar_file_path("a/B.XTF"));
  EXPECT_TRUE(is_sonar_file_name("line_0009.xtf"));
  try {
    SurveyInput mixed;
    mixed.paths = {kFile, "other.gsf"};
    load_survey(mixed);
    FAIL() << "two formats were read as one survey";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("must be of one format"));
  }
  try {
    read_survey({kFile, kFile});
    FAIL() << "a file given twice was read as a later one";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), testing::HasSubstr("give the files in time order"));
  }
}

}  // namespace
}  // namespace bathyslam::xtf
