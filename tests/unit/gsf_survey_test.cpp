// GSF as a Survey: real files mapped into the map frame, and a survey written as GSF and read
// back equal within the fields' resolution.
#include "core/io/gsf/gsf_survey.h"
#include "core/io/survey_input.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <iterator>

#include "core/io/gsf/big_endian.h"
#include "core/io/gsf/gsf_reader.h"
#include "core/io/gsf/gsf_writer.h"
#include "core/io/gsf/navigation_rewrite.h"
#include "core/summary/survey_summary.h"
#include "core/sync/nav_interpolation.h"
#include "core/types/pose.h"
#include "tests/unit/gsf_test_files.h"

namespace bathyslam::gsf {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

using test::kEx1811;
using test::kGsfpy;

fs::path temp_path(const std::string& name) {
  return fs::temp_directory_path() /
         ("bathyslam_gsf_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + name);
}

Eigen::Vector3d georeference(const Survey& survey, const bathyslam::Ping& ping, const Beam& beam) {
  const NavSample nav = *interpolate_nav(survey.nav, ping.time);
  return vehicle_pose(nav, {}) * Eigen::Vector3d(beam.along, beam.across, beam.down);
}

TEST(GsfSurvey, Ex1811SoundingsLandWhereTheGsfFilePutsThem) {
  const SurveyRead read = read_survey({kEx1811});
  const Survey& s = read.survey;
  EXPECT_EQ(s.metadata.crs, "EPSG:32620");  // 64.6 W is UTM zone 20
  ASSERT_EQ(s.nav.size(), 50u);
  ASSERT_EQ(s.pings.size(), 50u);
  EXPECT_EQ(s.beams.size(), read.files.front().soundings);
  EXPECT_EQ(s.metadata.sonar["format"], "GSF");
  EXPECT_EQ(s.metadata.sonar["sound_velocity_profiles"].size(), 1u);
  EXPECT_TRUE(s.metadata.sonar["processing_parameters"].contains("REFERENCE TIME"));

  FileSource source(kEx1811);
  const std::vector<Ping> gsf = test::pings_of(test::records_of(source, kEx1811.string()));
  for (std::size_t i = 0; i < s.pings.size(); ++i) {
    const Ping& g = gsf[i];
    EXPECT_DOUBLE_EQ(s.pings[i].time, g.time);
    EXPECT_DOUBLE_EQ(s.nav[i].heading_deg, g.heading_deg);
    EXPECT_DOUBLE_EQ(s.nav[i].depth_m, g.depth_corrector_m);
    for (const Beam& b : s.beams_of(s.pings[i])) {
      ASSERT_FALSE(g.beam_rejected(b.index));
      // Rolled and pitched back by the navigation, each sounding is at the GSF depth below the
      // surface and at the GSF along/across distance from the reference point.
      const Eigen::Vector3d p = georeference(s, s.pings[i], b);
      EXPECT_NEAR(p.z(), -g.depth_m[b.index], 1e-3);
      const Eigen::Vector2d offset(p.x() - s.nav[i].easting, p.y() - s.nav[i].northing);
      EXPECT_NEAR(offset.norm(), std::hypot(g.along_m[b.index], g.across_m[b.index]), 1e-3);
    }
  }
}

// What inspect reads: the same navigation and pings, each with its sounding count, no sounding.
TEST(GsfSurvey, ASurveyReadWithoutSoundingsCountsThem) {
  const Survey full = read_survey({kEx1811}).survey;
  const Survey counted = read_survey({kEx1811}, {"", std::nullopt, false}).survey;
  EXPECT_TRUE(counted.beams.empty());
  ASSERT_EQ(counted.pings.size(), full.pings.size());
  ASSERT_EQ(counted.nav.size(), full.nav.size());
  for (std::size_t i = 0; i < full.pings.size(); ++i) {
    EXPECT_EQ(counted.pings[i].time, full.pings[i].time);
    EXPECT_EQ(counted.pings[i].beam_count, full.pings[i].beam_count);
    EXPECT_EQ(counted.nav[i].easting, full.nav[i].easting);
  }
  EXPECT_EQ(to_json(summarize(counted)), to_json(summarize(full)));
}

// Keeps what it is handed, as a survey read whole holds it.
class KeptPings : public PingSink {
 public:
  std::size_t nav_at_begin = 0;
  std::vector<bathyslam::Ping> pings;
  std::vector<Beam> beams;
  void begin(const Survey& survey) override { nav_at_begin = survey.nav.size(); }
  void ping(double time, std::span<const Beam> b) override {
    pings.push_back({time, static_cast<std::uint32_t>(beams.size()), static_cast<std::uint32_t>(b.size())});
    beams.insert(beams.end(), b.begin(), b.end());
  }
};

// How a job reads GSF: the navigation first, then the soundings ping by ping, never all held.
TEST(GsfSurvey, StreamedSoundingsAreThoseOfTheSurveyReadWhole) {
  const std::vector<fs::path> files{kGsfpy, kEx1811};
  const Survey whole = read_survey(files).survey;
  Survey survey = read_survey(files, {"", std::nullopt, false}).survey;
  KeptPings kept;
  stream_soundings(files, survey, kept);
  EXPECT_TRUE(survey.pings.empty());
  EXPECT_EQ(survey.nav.size(), whole.nav.size());
  EXPECT_EQ(kept.nav_at_begin, whole.nav.size());
  ASSERT_EQ(kept.pings.size(), whole.pings.size());
  ASSERT_EQ(kept.beams.size(), whole.beams.size());
  ASSERT_GT(kept.beams.size(), 10000u);
  for (std::size_t i = 0; i < whole.pings.size(); ++i) {
    EXPECT_EQ(kept.pings[i].time, whole.pings[i].time);
    EXPECT_EQ(kept.pings[i].beam_count, whole.pings[i].beam_count);
  }
  for (std::size_t i = 0; i < whole.beams.size(); ++i) {
    ASSERT_EQ(kept.beams[i].index, whole.beams[i].index) << i;
    ASSERT_EQ(kept.beams[i].along, whole.beams[i].along) << i;
    ASSERT_EQ(kept.beams[i].across, whole.beams[i].across) << i;
    ASSERT_EQ(kept.beams[i].down, whole.beams[i].down) << i;
  }
}

TEST(GsfSurvey, StreamingFilesOtherThanThoseReadFirstIsRefused) {
  Survey survey = read_survey({kGsfpy, kEx1811}, {"", std::nullopt, false}).survey;
  KeptPings kept;
  try {
    stream_soundings({kEx1811}, survey, kept);
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("changed while it was read"));
  }
  EXPECT_TRUE(kept.pings.empty());
  Survey shorter = read_survey({kGsfpy}, {"", std::nullopt, false}).survey;
  EXPECT_THROW(stream_soundings({kGsfpy, kEx1811}, shorter, kept), std::runtime_error);
}

TEST(GsfSurvey, FilesOutOfTimeOrderAreRefused) {
  EXPECT_EQ(read_survey({kGsfpy, kEx1811}).survey.pings.size(), 54u);  // 2015, then 2018
  try {
    read_survey({kEx1811, kGsfpy});
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_THAT(e.what(), HasSubstr("gsfpy_test_data.gsf: record 7"));
    EXPECT_THAT(e.what(), HasSubstr("give the files in time order"));
  }
}

TEST(GsfSurvey, FilesOfUnknownOrderAreOrderedByTheirFirstPing) {
  EXPECT_EQ(sonar_files_in_time_order({kEx1811, kGsfpy}), (std::vector<fs::path>{kGsfpy, kEx1811}));
  EXPECT_EQ(sonar_files_in_time_order({kGsfpy, kEx1811}), (std::vector<fs::path>{kGsfpy, kEx1811}));
}

TEST(GsfSurvey, HeadingsAreStoredInHundredthsWithinOneTurn) {
  EXPECT_EQ(heading_field(0.0), 0);
  EXPECT_EQ(heading_field(180.004), 18000);
  EXPECT_EQ(heading_field(359.994), 35999);
  EXPECT_EQ(heading_field(359.996), 0);  // rounds to 360.00, which is 0
  EXPECT_EQ(heading_field(360.0), 0);
  EXPECT_EQ(heading_field(-0.004), 0);
  EXPECT_EQ(heading_field(-0.01), 35999);
  EXPECT_EQ(heading_field(725.5), 550);
}

TEST(GsfSurvey, UploadedFileNamesArePlainSonarFileNames) {
  EXPECT_TRUE(is_sonar_file_name("EX1811_EM302_0059_20181102_212138.gsf"));
  EXPECT_TRUE(is_sonar_file_name("line-2.GSF"));
  EXPECT_TRUE(is_sonar_file_name("0077_20221109_123655_Belgica.all"));
  EXPECT_FALSE(is_sonar_file_name("../survey.gsf"));
  EXPECT_FALSE(is_sonar_file_name("a/b.gsf"));
  EXPECT_FALSE(is_sonar_file_name(".gsf"));
  EXPECT_FALSE(is_sonar_file_name("survey.gsf.tmp"));
  EXPECT_FALSE(is_sonar_file_name("line 2.all"));
  EXPECT_FALSE(is_sonar_file_name("nav.csv"));
  EXPECT_FALSE(is_sonar_file_name(""));
}

TEST(GsfSurvey, RewrittenNavigationMovesThePingsAndKeepsEveryOtherByte) {
  const Survey original = read_survey({kEx1811}).survey;
  std::vector<NavSample> moved = original.nav;
  for (NavSample& n : moved) {
    n.easting += 10.0;
    n.northing -= 4.0;
    n.heading_deg = std::fmod(n.heading_deg + 1.5, 360.0);
  }
  const fs::path path = temp_path(".gsf");
  const RewriteCount count = rewrite_navigation(kEx1811, path, moved, original.metadata.crs);
  EXPECT_EQ(count.records, 73748u);
  EXPECT_EQ(count.pings, 50u);
  EXPECT_EQ(count.rewritten, 50u);
  EXPECT_EQ(fs::file_size(path), fs::file_size(kEx1811));
  {  // Only the 10 bytes of position and heading in each of the 50 ping headers may differ.
    std::ifstream fa(kEx1811, std::ios::binary), fb(path, std::ios::binary);
    const std::string ba{std::istreambuf_iterator<char>(fa), {}}, bb{std::istreambuf_iterator<char>(fb), {}};
    std::size_t differing = 0;
    for (std::size_t i = 0; i < ba.size() && i < bb.size(); ++i) differing += ba[i] != bb[i];
    EXPECT_GT(differing, 50u);
    EXPECT_LE(differing, 50u * 10u);
  }

  FileSource a_source(kEx1811), b_source(path);
  const std::vector<Record> a = test::records_of(a_source, "original"), b = test::records_of(b_source, "rewritten");
  ASSERT_EQ(a.size(), b.size());
  const Survey back = read_survey({path}, {original.metadata.crs, std::nullopt}).survey;
  fs::remove(path);
  std::size_t ping = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    ASSERT_EQ(a[i].index(), b[i].index()) << "record " << i + 1;
    if (const auto* pa = std::get_if<Ping>(&a[i])) {
      const Ping& pb = std::get<Ping>(b[i]);
      EXPECT_EQ(pb.time, pa->time);
      EXPECT_EQ(pb.depth_m, pa->depth_m);
      EXPECT_EQ(pb.across_m, pa->across_m);
      EXPECT_EQ(pb.beam_flags, pa->beam_flags);
      EXPECT_EQ(pb.roll_deg, pa->roll_deg);
      EXPECT_NEAR(std::remainder(pb.heading_deg - pa->heading_deg - 1.5, 360.0), 0.0, 0.006);
      EXPECT_NEAR(back.nav[ping].easting - original.nav[ping].easting, 10.0, 0.01);
      EXPECT_NEAR(back.nav[ping].northing - original.nav[ping].northing, -4.0, 0.01);
      ++ping;
    } else if (const auto* aa = std::get_if<Attitude>(&a[i])) {
      EXPECT_EQ(std::get<Attitude>(b[i]).roll_deg, aa->roll_deg);
    }
  }
  EXPECT_EQ(ping, 50u);
}

// A survey with turns, roll and pitch, and beams spread across 120 degrees, in UTM 51N.
Survey turning_survey() {
  Survey s;
  s.metadata.name = "turning";
  s.metadata.crs = "EPSG:32651";
  for (int i = 0; i < 200; ++i) {
    const double t = 1720000000.0 + 0.1 * i;
    s.nav.push_back({t, 452000.0 + 0.2 * i * std::cos(0.01 * i), 4630000.0 + 0.2 * i * std::sin(0.01 * i),
                     10.0 + 0.3 * std::sin(0.05 * i), 3.0 * std::sin(0.2 * i), -2.0 * std::cos(0.13 * i),
                     std::fmod(350.0 + 0.37 * i, 360.0)});
  }
  for (int p = 0; p < 150; ++p) {
    s.pings.push_back({1720000000.05 + 0.1 * p + 0.013 * (p % 3), static_cast<uint32_t>(s.beams.size()), 0});
    for (uint32_t b = 0; b < 64; ++b) {
      if ((b + p) % 17 == 0) continue;  // beams the sonar lost
      const double angle = (-60.0 + 120.0 * b / 63.0) * M_PI / 180.0;
      const double range = 15.0 + 0.1 * (p % 7);
      s.beams.push_back({b, static_cast<float>(0.05 * std::sin(b)), static_cast<float>(range * std::sin(angle)),
                         static_cast<float>(range * std::cos(angle))});
      ++s.pings.back().beam_count;
    }
  }
  return s;
}

TEST(GsfSurvey, WrittenAndReadBackEqualsTheSurveyWithinFieldResolution) {
  const Survey original = turning_survey();
  const fs::path path = temp_path(".gsf");
  EXPECT_EQ(write_survey(original, original.nav, path), original.pings.size());
  const Survey back = read_survey({path}).survey;
  fs::remove(path);

  EXPECT_EQ(back.metadata.crs, original.metadata.crs);  // the data's UTM zone is the survey's
  ASSERT_EQ(back.pings.size(), original.pings.size());
  ASSERT_EQ(back.beams.size(), original.beams.size());
  double worst_position = 0, worst_sounding = 0;
  for (std::size_t i = 0; i < original.pings.size(); ++i) {
    const bathyslam::Ping& a = original.pings[i];
    const bathyslam::Ping& b = back.pings[i];
    EXPECT_NEAR(b.time, a.time, 1e-6);  // nanoseconds, within a double's resolution
    ASSERT_EQ(b.beam_count, a.beam_count);
    const NavSample na = *interpolate_nav(original.nav, a.time);
    const NavSample& nb = back.nav[i];
    // Latitude/longitude in 1e-7 degree: about a centimetre.
    worst_position = std::max(worst_position, std::hypot(nb.easting - na.easting, nb.northing - na.northing));
    EXPECT_NEAR(nb.depth_m, na.depth_m, 0.005);  // centimetres
    EXPECT_NEAR(nb.roll_deg, na.roll_deg, 0.005);  // hundredths of a degree
    EXPECT_NEAR(nb.pitch_deg, na.pitch_deg, 0.005);
    EXPECT_NEAR(std::remainder(nb.heading_deg - na.heading_deg, 360.0), 0.0, 0.005);
    const auto beams_a = original.beams_of(a);
    const auto beams_b = back.beams_of(b);
    for (std::size_t k = 0; k < beams_a.size(); ++k) {
      ASSERT_EQ(beams_b[k].index, beams_a[k].index);
      const Eigen::Vector3d pa = georeference(original, a, beams_a[k]);
      const Eigen::Vector3d pb = georeference(back, b, beams_b[k]);
      worst_sounding = std::max(worst_sounding, (pb - pa).norm());
    }
  }
  EXPECT_LT(worst_position, 0.011);
  // The beams are written relative to the ping as stored, its rounding included, so only the
  // beam fields' 0.1 mm and float beams remain.
  EXPECT_LT(worst_sounding, 0.0002) << worst_sounding;
}

TEST(GsfSurvey, IgnoredPingsAndRejectedBeamsAreCountedNotKept) {
  const fs::path path = temp_path(".gsf");
  {
    Writer writer(path);
    for (int i = 0; i < 3; ++i) {
      Ping p;
      p.time = 1720000000.0 + i;
      p.longitude_deg = 123.0;
      p.latitude_deg = 41.8;
      p.num_beams = 4;
      p.depth_m = {20, 21, 22, 23};
      p.across_m = {-10, -3, 3, 10};
      p.along_m = {0, 0, 0, 0};
      p.beam_flags = {0, 1, 0, 0};
      if (i == 1) p.flags = 1;
      writer.write(p);
    }
    writer.close();
  }
  const SurveyRead read = read_survey({path});
  fs::remove(path);
  const FileSummary& f = read.files.front();
  EXPECT_EQ(f.pings, 3u);
  EXPECT_EQ(f.ignored_pings, 1u);
  EXPECT_EQ(f.beams, 8u);
  EXPECT_EQ(f.rejected_beams, 2u);
  EXPECT_EQ(f.soundings, 6u);
  EXPECT_EQ(read.survey.pings.size(), 2u);
  EXPECT_EQ(read.survey.nav.size(), 3u);  // an ignored ping's position is still navigation
  EXPECT_EQ(read.survey.beams.size(), 6u);
  EXPECT_EQ(read.survey.beams[1].index, 2u);
}

TEST(GsfSurvey, ValuesThatDoNotFitTheirFieldAreRefusedNamingThePing) {
  const fs::path path = temp_path(".gsf");
  Writer writer(path);
  Ping p;
  p.time = 1720000000.0;
  p.num_beams = 1;
  p.depth_m = {-1.0};  // above the surface: the depth field is unsigned
  p.across_m = {0.0};
  EXPECT_THAT([&] { writer.write(p); },
              ::testing::ThrowsMessage<std::runtime_error>(HasSubstr("ping 1: depth -1.000000 does not fit")));
  EXPECT_FALSE(fs::exists(path));  // nothing appears until closed
}

}  // namespace
}  // namespace bathyslam::gsf
