#include "core/io/bundle.h"
#include "core/io/bundle_files.h"
#include "core/io/tar_members.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace bathyslam {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;

Survey tiny_survey() {
  Survey s;
  s.metadata.name = "tiny";
  s.metadata.crs = "EPSG:32651";
  s.metadata.sonar = {{"model", "test"}, {"beams", 3}};
  s.metadata.vehicle = {{"model", "test auv"}};
  for (int i = 0; i < 5; ++i) {
    s.nav.push_back({1720000000.0 + i * 0.5, 452000.125 + i, 4630000.5, 1.25, 0.5, -0.25, 89.875});
  }
  s.reference_nav = s.nav;
  (*s.reference_nav)[3].easting += 0.3;
  for (int p = 0; p < 3; ++p) {
    s.pings.push_back({1720000000.1 + p * 0.7, static_cast<uint32_t>(s.beams.size()), 3});
    for (uint32_t b = 0; b < 3; ++b) {
      s.beams.push_back({b * 2, 0.0f, -5.125f + b * 5.0f, 9.875f + 0.001f * p});
    }
  }
  return s;
}

class BundleTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("bathyslam_bundle_" + std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
    write_bundle(tiny_survey(), dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::vector<std::string> lines_of(std::string_view file) {
    std::ifstream in(dir_ / file);
    std::vector<std::string> lines;
    for (std::string line; std::getline(in, line);) lines.push_back(line);
    return lines;
  }
  void write_lines(std::string_view file, const std::vector<std::string>& lines) {
    std::ofstream out(dir_ / file, std::ios::trunc);
    for (const auto& l : lines) out << l << '\n';
  }
  // Replaces line `number` (1-based) of `file`.
  void replace_line(std::string_view file, std::size_t number, const std::string& text) {
    auto lines = lines_of(file);
    lines.at(number - 1) = text;
    write_lines(file, lines);
  }
  // Reads the bundle, expecting it to fail; returns the problems as "file:line: ..." strings.
  std::string expect_rejected() {
    const BundleReadResult result = read_bundle(dir_);
    EXPECT_FALSE(result.survey.has_value()) << "a bad bundle must yield no survey";
    std::string all;
    for (const Problem& p : result.problems) all += p.to_string() + "\n";
    return all;
  }

  fs::path dir_;
};

TEST_F(BundleTest, RoundTripKeepsEveryValueExactly) {
  const Survey original = tiny_survey();
  const BundleReadResult result = read_bundle(dir_);
  ASSERT_TRUE(result.survey) << (result.problems.empty() ? "" : result.problems[0].to_string());
  EXPECT_TRUE(result.problems.empty());
  const Survey& read = *result.survey;
  EXPECT_EQ(read.metadata.name, original.metadata.name);
  EXPECT_EQ(read.metadata.crs, original.metadata.crs);
  EXPECT_EQ(read.metadata.sonar, original.metadata.sonar);
  EXPECT_EQ(read.metadata.vehicle, original.metadata.vehicle);
  ASSERT_EQ(read.nav.size(), original.nav.size());
  for (std::size_t i = 0; i < read.nav.size(); ++i) {
    EXPECT_EQ(read.nav[i].time, original.nav[i].time);
    EXPECT_EQ(read.nav[i].easting, original.nav[i].easting);
    EXPECT_EQ(read.nav[i].heading_deg, original.nav[i].heading_deg);
    EXPECT_EQ((*read.reference_nav)[i].easting, (*original.reference_nav)[i].easting);
  }
  ASSERT_EQ(read.pings.size(), original.pings.size());
  ASSERT_EQ(read.beams.size(), original.beams.size());
  for (std::size_t p = 0; p < read.pings.size(); ++p) {
    EXPECT_EQ(read.pings[p].time, original.pings[p].time);
    EXPECT_EQ(read.pings[p].beam_count, original.pings[p].beam_count);
  }
  for (std::size_t b = 0; b < read.beams.size(); ++b) {
    EXPECT_EQ(read.beams[b].index, original.beams[b].index);
    EXPECT_EQ(read.beams[b].across, original.beams[b].across);
    EXPECT_EQ(read.beams[b].down, original.beams[b].down);
  }
  // Writing what was read gives the same bytes.
  const fs::path again = dir_.string() + "_again";
  write_bundle(read, again);
  for (auto file : {kNavFile, kPingsFile, kSurveyJsonFile, kReferenceNavFile}) {
    std::ifstream a(dir_ / file), b(again / file);
    std::stringstream sa, sb;
    sa << a.rdbuf();
    sb << b.rdbuf();
    EXPECT_EQ(sa.str(), sb.str()) << file;
  }
  fs::remove_all(again);
}

TEST_F(BundleTest, ReferenceNavIsOptional) {
  fs::remove(dir_ / kReferenceNavFile);
  const BundleReadResult result = read_bundle(dir_);
  ASSERT_TRUE(result.survey);
  EXPECT_FALSE(result.survey->reference_nav);
}

TEST_F(BundleTest, UnknownEpsgCodeIsNamedWithLineAndField) {
  auto lines = lines_of(kSurveyJsonFile);
  for (auto& l : lines) {
    if (l.find("\"crs\"") != std::string::npos) l = "  \"crs\": \"EPSG:999999\",";
  }
  write_lines(kSurveyJsonFile, lines);
  const std::string problems = expect_rejected();
  EXPECT_THAT(problems, HasSubstr("survey.json:2: crs: 'EPSG:999999' is not a CRS that PROJ knows"));
}

TEST_F(BundleTest, GeographicCrsIsRejected) {
  auto lines = lines_of(kSurveyJsonFile);
  for (auto& l : lines) {
    if (l.find("\"crs\"") != std::string::npos) l = "  \"crs\": \"EPSG:4326\",";
  }
  write_lines(kSurveyJsonFile, lines);
  EXPECT_THAT(expect_rejected(), HasSubstr("crs: 'EPSG:4326' (WGS 84) is not a projected CRS"));
}

TEST_F(BundleTest, CrsMustBeAnEpsgCode) {
  write_lines(kSurveyJsonFile, {R"({"name": "x", "crs": "UTM 51N"})"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json:1: crs: 'UTM 51N' is not of the form EPSG:<code>"));
}

TEST_F(BundleTest, MissingNameAndBrokenJson) {
  write_lines(kSurveyJsonFile, {R"({"crs": "EPSG:32651"})"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json:1: name: missing"));
  write_lines(kSurveyJsonFile, {"{", R"(  "name": "x",)", R"(  "crs": EPSG)", "}"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json:3: not valid JSON"));
}

// Nesting is what crashes a JSON consumer (copies and dumps recurse per level), not the parse:
// the reader refuses it before any copy is made.
TEST_F(BundleTest, SurveyJsonNestedTooDeepOrTooLargeIsRefused) {
  const std::string deep(100000, '[');
  write_lines(kSurveyJsonFile, {R"({"name": "x", "crs": "EPSG:32651", "sonar": {"a": )" + deep + std::string(100000, ']') + "}}"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json: nested deeper than 64 levels"));
  write_lines(kSurveyJsonFile, {R"({"name": "x", "crs": "EPSG:32651", "sonar": {"a": ")" + std::string(2 << 20, 'x') + "\"}}"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json: larger than 1048576 bytes"));
  // 63 levels inside the document's own object are fine.
  write_lines(kSurveyJsonFile, {R"({"name": "x", "crs": "EPSG:32651", "sonar": {"a": )" + std::string(62, '[') +
                                std::string(62, ']') + "}}"});
  EXPECT_TRUE(read_bundle(dir_).survey);
}

TEST(BoundedJson, LimitsAreExactAndSyntaxErrorsStayParseErrors) {
  const JsonLimits limits{.max_bytes = 100, .max_depth = 3};
  EXPECT_EQ(parse_bounded_json("[[[1]]]", limits), nlohmann::json::parse("[[[1]]]"));
  EXPECT_THROW(parse_bounded_json("[[[[1]]]]", limits), JsonLimitError);
  EXPECT_THROW(parse_bounded_json(R"({"a": {"b": {"c": {}}}})", limits), JsonLimitError);
  EXPECT_THROW(parse_bounded_json(std::string(101, ' ') + "1", limits), JsonLimitError);
  EXPECT_THROW(parse_bounded_json("[1,", limits), nlohmann::json::parse_error);
  // A number no double holds: refused like a limit, never an exception the callers do not expect
  // (the bundle fuzzer's crash-d3cb2ee8: survey.json "6e524").
  EXPECT_THROW(parse_bounded_json("6e524", limits), JsonLimitError);
}

TEST_F(BundleTest, ANumberBeyondADoubleInSurveyJsonIsAProblemNotACrash) {
  write_lines(kSurveyJsonFile, {R"({"name": "x", "crs": "EPSG:32651", "sonar": {"a": 6e524}})"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json: a number out of range"));
}

// "\u0000" is valid JSON, but no survey holding it could be stored (PostgreSQL's jsonb and text
// refuse it): refused where it is parsed, in a key or a value at any depth.
TEST(BoundedJson, AStringHoldingNulIsRefused) {
  for (const char* text : {R"({"a": "\u0000"})", R"({"a": [{"b\u0000": 1}]})", R"(["x\u0000y"])"})
    EXPECT_THROW(parse_bounded_json(text), JsonLimitError) << text;
  EXPECT_EQ(parse_bounded_json(R"({"a": "\u0001"})")["a"], "\x01");  // other escapes stay valid
}

TEST_F(BundleTest, ANulInSurveyJsonIsAProblem) {
  write_lines(kSurveyJsonFile, {R"({"name": "t\u0000", "crs": "EPSG:32651"})"});
  EXPECT_THAT(expect_rejected(), HasSubstr("survey.json: a string holds \\u0000"));
}

TEST_F(BundleTest, ALineTooLongIsNamedAndEndsTheFile) {
  replace_line(kNavFile, 3, std::string(100000, '1'));
  replace_line(kPingsFile, 1, std::string(100000, 't'));
  const std::string problems = expect_rejected();
  EXPECT_THAT(problems, HasSubstr("nav.csv:3: line longer than 65536 bytes; the rest of the file was not read"));
  EXPECT_THAT(problems, HasSubstr("pings.csv:1: line longer than 65536 bytes"));
}

TEST_F(BundleTest, NavHeaderMustBeExact) {
  replace_line(kNavFile, 1, "time,easting,northing,depth,roll,pitch,yaw");
  EXPECT_THAT(expect_rejected(),
              HasSubstr("nav.csv:1: header is 'time,easting,northing,depth,roll,pitch,yaw'; "
                        "expected exactly 'time,easting,northing,depth,roll,pitch,heading'"));
}

TEST_F(BundleTest, AHeaderOfControlBytesAndLatin1IsQuotedPrintably) {
  replace_line(kNavFile, 1, std::string("ti\0me,\xe9" "asting\x01", 14));
  // A database's text column and a JSON encoder refuse NUL and bytes that are not UTF-8.
  EXPECT_THAT(expect_rejected(), HasSubstr("nav.csv:1: header is 'ti\\x00me,\\xe9asting\\x01'"));
}

TEST(Printable, KeepsUtf8AndEscapesWhatIsNot) {
  EXPECT_EQ(printable("500 m \xc3\x97 2 m, caf\xc3\xa9"), "500 m \xc3\x97 2 m, caf\xc3\xa9");
  EXPECT_EQ(printable(std::string("a\0b\tc\x7f", 6)), "a\\x00b\\x09c\\x7f");
  EXPECT_EQ(printable("\xe9t\xe9"), "\\xe9t\\xe9");          // Latin-1
  EXPECT_EQ(printable("\xc0\xaf"), "\\xc0\\xaf");            // an overlong '/'
  EXPECT_EQ(printable("\xed\xa0\x80"), "\\xed\\xa0\\x80");  // a UTF-16 surrogate
  EXPECT_EQ(printable("\xf0\x9f\x8c\x8a"), "\xf0\x9f\x8c\x8a");  // U+1F30A, four bytes
  EXPECT_EQ(printable("\xe2\x82"), "\\xe2\\x82");            // cut short at the end
}

TEST(QuotedInput, QuotesAtMost64BytesAndSaysHowLongTheInputWas) {
  EXPECT_EQ(quoted_input("nav.csv"), "'nav.csv'");
  EXPECT_EQ(quoted_input(std::string("coll\0one", 8)), "'coll\\x00one'");
  EXPECT_EQ(quoted_input(std::string(64, 'x')), "'" + std::string(64, 'x') + "'");
  EXPECT_EQ(quoted_input(std::string(1'900'000, 'x')), "'" + std::string(64, 'x') + "\u2026' (1900000 bytes)");
  // Cut before a UTF-8 sequence that the 64th byte falls inside, not through it.
  const std::string accents = std::string(63, 'a') + "\xc3\xa9" + "tail";
  EXPECT_EQ(quoted_input(accents), "'" + std::string(63, 'a') + "\u2026' (69 bytes)");
}

// A tar of the test's bundle folder as GNU tar makes it (`options` before the file list), the
// folder changed first by `prepare`.
class TarBundleTest : public BundleTest {
 protected:
  fs::path tar_of_bundle(const std::string& options = "") {
    const fs::path tar = dir_.string() + ".tar";
    const std::string command = "tar " + options + " -cf '" + tar.string() + "' -C '" + dir_.parent_path().string() + "' '" +
                                dir_.filename().string() + "'";
    EXPECT_EQ(std::system(command.c_str()), 0) << command;
    return tar;
  }
  std::string refusal_of(const fs::path& tar) {
    try {
      BundleFiles files(tar);
    } catch (const std::runtime_error& error) {
      return error.what();
    }
    return "accepted";
  }
  void TearDown() override {
    fs::remove(dir_.string() + ".tar");
    BundleTest::TearDown();
  }
};

TEST_F(TarBundleTest, AMemberThatIsASymbolicLinkIsRefusedNamingIt) {
  fs::remove(dir_ / kPingsFile);
  fs::create_symlink("/etc/hostname", dir_ / kPingsFile);
  const std::string member = dir_.filename().string() + "/pings.csv";
  EXPECT_THAT(refusal_of(tar_of_bundle()), HasSubstr("'" + member + "' is a symbolic link to '/etc/hostname'"));
}

TEST_F(TarBundleTest, AMemberThatIsAHardLinkIsRefusedNamingIt) {
  fs::remove(dir_ / kReferenceNavFile);
  fs::create_hard_link(dir_ / kNavFile, dir_ / kReferenceNavFile);
  EXPECT_THAT(refusal_of(tar_of_bundle()), HasSubstr("is a hard link to"));
}

TEST_F(TarBundleTest, LongNamesAndLinksAreReadInEveryFormat) {
  // Paths over ustar's 100-byte name field: a prefix field in ustar, a long-name header in GNU's
  // format, a "path" record in pax.
  const std::string folder(80, 'f');
  fs::create_directory(dir_ / folder);
  fs::create_symlink(std::string(90, 't'), dir_ / folder / "link");
  for (const std::string format : {"gnu", "pax", "ustar"}) {
    const std::vector<TarMember> members = tar_members(tar_of_bundle("--format=" + format));
    const auto link = std::find_if(members.begin(), members.end(), [](const TarMember& m) { return m.type == '2'; });
    ASSERT_NE(link, members.end()) << format;
    EXPECT_EQ(link->name, dir_.filename().string() + "/" + folder + "/link") << format;
    EXPECT_EQ(link->link, std::string(90, 't')) << format;
    EXPECT_EQ(std::count_if(members.begin(), members.end(), [](const TarMember& m) { return m.type == '0'; }), 4) << format;
  }
}

// A header whose size runs past the file's end ends the walk. Here GNU's base-256 form of
// 2^64 - 512: rounded up to whole blocks it was a seek of -512 bytes, back onto the same header,
// and the walk listed it forever (found by fuzzing).
TEST_F(TarBundleTest, AMemberSizeBeyondTheFileEndsTheWalk) {
  const fs::path tar = tar_of_bundle("--format=gnu");
  {
    std::fstream f(tar, std::ios::binary | std::ios::in | std::ios::out);
    f.seekp(124);
    f.put(static_cast<char>(0x80));
    for (int i = 1; i < 10; ++i) f.put(static_cast<char>(0xff));
    f.put(static_cast<char>(0xfe));
    f.put('\0');
  }
  EXPECT_TRUE(tar_members(tar).empty());
  EXPECT_THAT(refusal_of(tar), HasSubstr(tar.string()));
}

TEST_F(TarBundleTest, AnEmptyMemberReadsAsNoBytes) {
  write_lines(kReferenceNavFile, {});
  const BundleFiles files(tar_of_bundle());
  ASSERT_EQ(files.size(kReferenceNavFile), 0u);
  char buffer[1024];
  EXPECT_EQ(files.open(kReferenceNavFile)->read(buffer, sizeof buffer), 0u) << "the tar's next header read as the file";
  EXPECT_EQ(read_at_most(*files.open(kNavFile), 1 << 20).size(), files.size(kNavFile));
}

TEST_F(BundleTest, NavNanIsNamedWithLineAndColumn) {
  replace_line(kNavFile, 3, "1720000000.5,nan,4630000.5,1.25,0.5,-0.25,89.875");
  EXPECT_THAT(expect_rejected(), HasSubstr("nav.csv:3: easting: not finite: 'nan'"));
}

TEST_F(BundleTest, NavInfinityAndGarbage) {
  replace_line(kNavFile, 2, "1720000000,452000.125,4630000.5,inf,0.5,-0.25,north");
  const std::string problems = expect_rejected();
  EXPECT_THAT(problems, HasSubstr("nav.csv:2: depth: not finite: 'inf'"));
  EXPECT_THAT(problems, HasSubstr("nav.csv:2: heading: not a number: 'north'"));
}

TEST_F(BundleTest, NavTimeGoingBackwards) {
  replace_line(kNavFile, 4, "1719999999,452002.125,4630000.5,1.25,0.5,-0.25,89.875");
  EXPECT_THAT(expect_rejected(), HasSubstr("nav.csv:4: time: goes backwards: 1719999999"));
}

TEST_F(BundleTest, NavWrongFieldCountAndAttitudeRange) {
  replace_line(kNavFile, 2, "1720000000,452000.125,4630000.5");
  replace_line(kNavFile, 5, "1720000001.5,452003.125,4630000.5,1.25,95,-0.25,89.875");
  const std::string problems = expect_rejected();
  EXPECT_THAT(problems, HasSubstr("nav.csv:2: 3 fields; expected 7"));
  EXPECT_THAT(problems, HasSubstr("nav.csv:5: roll: outside ±90°"));
}

// A finite number that is no position (issue 37: an easting of 1e300 finalized, then every job
// failed at the map stage, or ran out of memory offline).
TEST_F(BundleTest, NavPositionsAndDepthsNoSurveyCanHave) {
  replace_line(kNavFile, 3, "1720000000.5,1e300,4630000.5,1.25,0.5,-0.25,89.875");
  replace_line(kNavFile, 4, "1720000001,452002.125,-2e8,1.25,0.5,-0.25,89.875");
  replace_line(kNavFile, 5, "1720000001.5,452003.125,4630000.5,15000,0.5,-0.25,89.875");
  const std::string problems = expect_rejected();
  EXPECT_THAT(problems, HasSubstr("nav.csv:3: easting: '1e300' m is no projected coordinate (beyond ±1e8 m)"));
  EXPECT_THAT(problems, HasSubstr("nav.csv:4: northing: '-2e8' m is no projected coordinate"));
  EXPECT_THAT(problems, HasSubstr("nav.csv:5: depth: '15000' m is beyond ±12000 m"));
}

TEST_F(BundleTest, NavWithoutSamples) {
  write_lines(kNavFile, {std::string(kNavHeader)});
  EXPECT_THAT(expect_rejected(), HasSubstr("nav.csv: needs at least 2 navigation samples, has 0"));
}

TEST_F(BundleTest, ReferenceNavIsValidatedToo) {
  replace_line(kReferenceNavFile, 6, "1720000002,452004.125,4630000.5,1.25,0.5,-0.25,");
  EXPECT_THAT(expect_rejected(), HasSubstr("reference_nav.csv:6: heading: not a number: ''"));
}

TEST_F(BundleTest, PingsHeaderMustBeExact) {
  replace_line(kPingsFile, 1, "time,beam,x,y,z");
  EXPECT_THAT(expect_rejected(), HasSubstr("pings.csv:1: header is 'time,beam,x,y,z'"));
}

TEST_F(BundleTest, PingInfinityIsNamedWithLineAndColumn) {
  replace_line(kPingsFile, 5, "1720000000.8,0,0,-inf,9.876");
  EXPECT_THAT(expect_rejected(), HasSubstr("pings.csv:5: across: not finite: '-inf'"));
}

TEST_F(BundleTest, PingBeamsMustIncreaseWithinAPing) {
  replace_line(kPingsFile, 4, "1720000000.1,2,0,4.875,9.875");
  EXPECT_THAT(expect_rejected(),
              HasSubstr("pings.csv:4: beam: beam 2 follows beam 2 in the same ping"));
}

TEST_F(BundleTest, PingNegativeBeamIndex) {
  replace_line(kPingsFile, 2, "1720000000.1,-1,0,-5.125,9.875");
  EXPECT_THAT(expect_rejected(), HasSubstr("pings.csv:2: beam: not a number: '-1'"));
}

TEST_F(BundleTest, PingTimeGoingBackwards) {
  replace_line(kPingsFile, 6, "1720000000,0,0,-5.125,9.876");
  EXPECT_THAT(expect_rejected(), HasSubstr("pings.csv:6: time: goes backwards"));
}

TEST_F(BundleTest, MissingPingsFile) {
  fs::remove(dir_ / kPingsFile);
  EXPECT_THAT(expect_rejected(), HasSubstr("pings.csv: missing from"));
}

TEST_F(BundleTest, PingsOutsideNavigationAreReportedButKept) {
  // Navigation now ends at 1720000001.0: the last ping (1720000001.5) lies outside it.
  auto nav = lines_of(kNavFile);
  nav.resize(4);
  write_lines(kNavFile, nav);
  const BundleReadResult result = read_bundle(dir_);
  ASSERT_TRUE(result.survey);
  ASSERT_EQ(result.problems.size(), 1u);
  EXPECT_EQ(result.problems[0].severity, Problem::Severity::kWarning);
  EXPECT_THAT(result.problems[0].to_string(),
              HasSubstr("pings.csv:8: warning: time: 1 pings lie outside the navigation's time span"));
}

TEST_F(BundleTest, ProblemsAreCappedPerFileWithACount) {
  auto lines = lines_of(kPingsFile);
  for (int i = 0; i < 200; ++i) lines.push_back("1720000001.9,x,0,0,0");
  write_lines(kPingsFile, lines);
  const BundleReadResult result = read_bundle(dir_);
  EXPECT_FALSE(result.survey);
  ASSERT_EQ(result.problems.size(), 51u);
  EXPECT_EQ(result.problems.back().to_string(), "pings.csv: 150 more problems not listed");
}

// The two navigations are read on two threads; their problems still come in file order (nav.csv's,
// reference_nav.csv's, pings.csv's), each file capped with its own count.
TEST_F(BundleTest, ProblemsOfBothNavigationsComeInFileOrderEachCapped) {
  for (std::string_view file : {kNavFile, kReferenceNavFile}) {
    auto lines = lines_of(file);
    for (int i = 0; i < 60; ++i) lines.push_back("1720000009,x,4630000.5,1.25,0.5,-0.25,89.875");
    write_lines(file, lines);
  }
  replace_line(kPingsFile, 2, "1720000000.1,0,0,0,north");
  const BundleReadResult result = read_bundle(dir_);
  EXPECT_FALSE(result.survey);
  ASSERT_EQ(result.problems.size(), 50u + 50u + 1u + 2u);
  for (std::size_t i = 0; i < 50; ++i) EXPECT_EQ(result.problems[i].file, kNavFile) << i;
  for (std::size_t i = 50; i < 100; ++i) EXPECT_EQ(result.problems[i].file, kReferenceNavFile) << i;
  EXPECT_EQ(result.problems[100].file, kPingsFile);
  EXPECT_EQ(result.problems[101].to_string(), "nav.csv: 10 more problems not listed");
  EXPECT_EQ(result.problems[102].to_string(), "reference_nav.csv: 10 more problems not listed");
}

TEST_F(BundleTest, LoadBundleThrowsWithEveryError) {
  replace_line(kNavFile, 3, "1720000000.5,nan,4630000.5,1.25,0.5,-0.25,89.875");
  replace_line(kPingsFile, 5, "1720000000.8,0,0,-inf,9.876");
  try {
    load_bundle(dir_);
    FAIL() << "expected BundleError";
  } catch (const BundleError& e) {
    EXPECT_EQ(e.problems().size(), 2u);
    EXPECT_THAT(e.what(), HasSubstr("nav.csv:3: easting"));
    EXPECT_THAT(e.what(), HasSubstr("pings.csv:5: across"));
  }
}

// What a sink saw: the survey as begin() got it, then each ping.
class RecordingSink : public PingSink {
 public:
  void begin(const Survey& survey) override {
    nav_at_begin = survey.nav.size();
    reference_at_begin = survey.reference_nav.has_value();
    pings_before_begin = pings.size();
  }
  void ping(double time, std::span<const Beam> beams) override {
    pings.push_back({time, static_cast<uint32_t>(this->beams.size()), static_cast<uint32_t>(beams.size())});
    this->beams.insert(this->beams.end(), beams.begin(), beams.end());
  }
  std::size_t nav_at_begin = 0, pings_before_begin = 99;
  bool reference_at_begin = false;
  std::vector<Ping> pings;
  std::vector<Beam> beams;
};

TEST_F(BundleTest, StreamingHandsOnEveryPingAfterBothNavigations) {
  const Survey original = tiny_survey();
  RecordingSink sink;
  const BundleReadResult result = stream_bundle(dir_, sink);
  ASSERT_TRUE(result.survey);
  EXPECT_EQ(sink.nav_at_begin, original.nav.size()) << "a submap builder needs the navigation first";
  EXPECT_TRUE(sink.reference_at_begin) << "and the reference, for each submap's reference pose";
  EXPECT_EQ(sink.pings_before_begin, 0u);
  EXPECT_TRUE(result.survey->pings.empty());
  EXPECT_TRUE(result.survey->beams.empty());
  EXPECT_EQ(result.survey->nav.size(), original.nav.size());
  ASSERT_EQ(sink.pings.size(), original.pings.size());
  for (std::size_t p = 0; p < original.pings.size(); ++p) {
    EXPECT_EQ(sink.pings[p].time, original.pings[p].time);
    ASSERT_EQ(sink.pings[p].beam_count, original.pings[p].beam_count);
    for (uint32_t b = 0; b < original.pings[p].beam_count; ++b) {
      const Beam& got = sink.beams[sink.pings[p].first_beam + b];
      const Beam& want = original.beams[original.pings[p].first_beam + b];
      EXPECT_EQ(got.index, want.index);
      EXPECT_EQ(got.along, want.along);
      EXPECT_EQ(got.across, want.across);
      EXPECT_EQ(got.down, want.down);
    }
  }
}

TEST_F(BundleTest, StreamingABundleWithAnErrorGivesNoSurvey) {
  replace_line(kPingsFile, 8, "1720000001.5,4,0,nan,9.877");
  RecordingSink sink;
  const BundleReadResult result = stream_bundle(dir_, sink);
  EXPECT_FALSE(result.survey) << "the caller must discard what the sink made";
  EXPECT_EQ(sink.pings.size(), 3u) << "the error is in the last ping: the others went on";
  ASSERT_EQ(result.problems.size(), 1u);
  EXPECT_THAT(result.problems[0].to_string(), HasSubstr("pings.csv:8: across: not finite: 'nan'"));
}

}  // namespace
}  // namespace bathyslam
