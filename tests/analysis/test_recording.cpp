// Reading recording CSV files: line endings, chunk boundaries, the column
// map, error messages, and the UMich data set read through a map.
#include <gtest/gtest.h>

#include <fstream>
#include <string>

#include "test_paths.hpp"
#include "truecut/analysis/recording.hpp"

namespace truecut::analysis {
namespace {

std::filesystem::path write(const std::string& name, const std::string& text) {
  auto p = test::scratch_dir() / name;
  std::ofstream(p, std::ios::binary) << text;
  return p;
}

std::string with_endings(const std::string& lf_text, const std::string& eol) {
  std::string out;
  for (char c : lf_text)
    out += c == '\n' ? eol : std::string(1, c);
  return out;
}

std::string error_of(const std::filesystem::path& p, const RecordingOptions& o = {}) {
  try {
    read_recording(p, o);
  } catch (const RecordingError& e) {
    return e.what();
  }
  return "(no error)";
}

const std::string kSmall = "t,x_cmd,x_act,note\n0,1.5,1.25,a\n0.1,2,2.5e-1,b c\n\n0.2,-3,+4,\n";

TEST(Recording, ReadsLfCrlfAndCrAlike) {
  for (const std::string eol : {"\n", "\r\n", "\r"}) {
    SCOPED_TRACE(eol == "\r" ? "CR" : eol == "\n" ? "LF" : "CRLF");
    auto rec = read_recording(write("small.csv", with_endings(kSmall, eol)));
    ASSERT_EQ(rec.rows(), 3u);
    EXPECT_EQ(rec.t_s, (std::vector<double>{0, 0.1, 0.2}));
    EXPECT_EQ(rec.channel("x_cmd"), (std::vector<double>{1.5, 2, -3}));
    EXPECT_EQ(rec.channel("x_act"), (std::vector<double>{1.25, 0.25, 4}));
    EXPECT_FALSE(rec.has("note"));  // not a channel, and not parsed
    EXPECT_EQ(rec.columns.size(), 4u);
  }
}

TEST(Recording, CrlfSplitAcrossReadChunks) {
  // The reader takes 64 KiB at a time: put a CR as the last byte of the first
  // chunk so that its LF starts the second one.
  std::string text = "t,x_cmd,x_act\r\n";
  std::string pad_row = "0,1,1";
  const std::size_t used = text.size();
  pad_row += std::string(65535 - used - pad_row.size(), ' ');  // trailing blanks are trimmed
  text += pad_row + "\r\n";
  ASSERT_EQ(text[65535], '\r');
  ASSERT_EQ(text[65536], '\n');
  std::size_t rows = 1;
  for (int i = 1; i < 20000; ++i, ++rows)
    text += std::to_string(i) + ",1,1\r\n";
  auto rec = read_recording(write("chunks.csv", text));
  EXPECT_EQ(rec.rows(), rows);
  EXPECT_EQ(rec.t_s.back(), double(rows - 1));
}

TEST(Recording, MapRenamesScalesAndSynthesisesTime) {
  auto p = write("foreign.csv", "\"Pos Cmd\",PosAct_um\n10,10004\n11,11002\n12,11998\n");
  RecordingOptions o;
  o.map = parse_column_map("x_cmd=Pos Cmd, x_act=PosAct_um*0.001 ,t=@index*0.25");
  auto rec = read_recording(p, o);
  ASSERT_EQ(rec.rows(), 3u);
  EXPECT_EQ(rec.t_s, (std::vector<double>{0, 0.25, 0.5}));
  EXPECT_EQ(rec.channel("x_cmd"), (std::vector<double>{10, 11, 12}));
  EXPECT_NEAR(rec.channel("x_act")[1], 11.002, 1e-12);
  EXPECT_EQ(rec.measured("x"), &rec.channel("x_act"));
}

TEST(Recording, MeasPreferredOverAct) {
  auto rec = read_recording(write("m.csv", "t,x_cmd,x_act,x_meas\n0,1,2,3\n"));
  EXPECT_EQ((*rec.measured("x"))[0], 3);
  EXPECT_EQ(rec.measured("y"), nullptr);
}

TEST(Recording, StreamsRowsInOrder) {
  auto p = write("s.csv", kSmall);
  std::vector<double> times;
  auto header =
      stream_recording(p, {}, [&](const RecordingHeader& h, const std::vector<double>& row) {
        ASSERT_EQ(h.channels[0], "t");
        times.push_back(row[0]);
      });
  EXPECT_EQ(times, (std::vector<double>{0, 0.1, 0.2}));
  EXPECT_EQ(header.channels, (std::vector<std::string>{"t", "x_cmd", "x_act"}));
}

TEST(RecordingErrors, MissingColumnListsAvailable) {
  auto p = write("e.csv", "t,x_cmd,x_act\n0,1,1\n");
  RecordingOptions o;
  o.required = {"y_cmd"};
  const auto msg = error_of(p, o);
  EXPECT_NE(msg.find(p.string() + ":1: no column for 'y_cmd'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("available: t, x_cmd, x_act"), std::string::npos) << msg;

  o = {};
  o.map = parse_column_map("x_cmd=Xc");
  EXPECT_NE(error_of(p, o).find("no column 'Xc'"), std::string::npos);

  auto no_t = write("no_t.csv", "x_cmd\n1\n");
  EXPECT_NE(error_of(no_t).find("no time column 't'"), std::string::npos);
  EXPECT_NE(error_of(no_t).find("@index"), std::string::npos);
}

TEST(RecordingErrors, NonNumericCellNamesFileLineAndColumn) {
  auto p = write("bad.csv", "t,x_cmd,x_act\n0,1,1\r\n0.1,1,oops\n");
  const auto msg = error_of(p);
  EXPECT_NE(msg.find(p.string() + ":3: column 3 'x_act': 'oops' is not a finite number"),
            std::string::npos)
      << msg;

  RecordingOptions o;
  o.map = parse_column_map("x_act=Enc");
  auto q = write("bad2.csv", "t,x_cmd,Enc\n0,1,\n");
  const auto msg2 = error_of(q, o);
  EXPECT_NE(msg2.find(":2: column 3 'Enc' (x_act): '' is not a finite number"), std::string::npos)
      << msg2;

  auto r = write("short.csv", "t,x_cmd,x_act\n0,1\n");
  EXPECT_NE(error_of(r).find(":2: column 3 'x_act': missing"), std::string::npos) << error_of(r);
}

TEST(RecordingErrors, TimeMustIncrease) {
  auto p = write("time.csv", "t,x_cmd\r0,1\r0.1,1\r0.1,2\r");
  const auto msg = error_of(p);
  EXPECT_NE(msg.find(p.string() + ":4: column 1 't': time 0.1 s is not after 0.1 s on line 3"),
            std::string::npos)
      << msg;
}

// Issue 23 (sweep F11): a header naming a channel twice (the second x_act
// 5 mm off) was read taking one of the columns without a word.
TEST(RecordingErrors, AChannelNamedTwiceIsAmbiguous) {
  auto p = write("dup.csv", "t,x_cmd,x_act,x_act\n0,1,1,6\n0.1,2,2,7\n");
  const auto msg = error_of(p);
  EXPECT_NE(
      msg.find(p.string() + ":1: columns 3 and 4 are both named 'x_act': an ambiguous channel"),
      std::string::npos)
      << msg;
  // A column the channels do not use may repeat.
  auto q = write("dup_note.csv", "t,x_cmd,x_act,note,note\n0,1,1,a,b\n0.1,2,2,c,d\n");
  EXPECT_EQ(read_recording(q).rows(), 2u);
}

// Issue 23 (sweep, low): a camonitor date that does not exist, or a stamp
// centuries from the others (t of 2.5e11 s, beyond the recordings' 1e9 s),
// was read.
TEST(RecordingErrors, CamonitorStampsMustExistAndStayWithinTheTimeRange) {
  RecordingOptions o;
  o.map = parse_column_map("x_cmd=X:Cmd,x_act=X:Act");
  auto bad_day =
      write("day.log", "X:Cmd 2022-02-28 10:00:00.000000 1\nX:Act 2022-02-30 10:00:00.000000 1\n");
  std::string msg;
  try {
    read_camonitor(bad_day, o);
  } catch (const RecordingError& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("day.log:2: PV 'X:Act': bad time stamp '2022-02-30 10:00:00.000000'"),
            std::string::npos)
      << msg;
  auto far = write("far.log",
                   "X:Cmd 2022-02-28 10:00:00.000000 1\nX:Act 2022-02-28 10:00:00.000000 1\n"
                   "X:Act 9999-01-01 10:00:00.000000 2\n");
  msg.clear();
  try {
    read_camonitor(far, o);
  } catch (const RecordingError& e) {
    msg = e.what();
  }
  EXPECT_NE(msg.find("far.log:3: time stamp '9999-01-01 10:00:00.000000' is "), std::string::npos)
      << msg;
  EXPECT_NE(msg.find("after the stamp '2022-02-28 10:00:00.000000' on line 1"), std::string::npos)
      << msg;
  auto leap = write("leap.log",
                    "X:Cmd 2024-02-29 10:00:00.000000 1\nX:Act 2024-02-29 10:00:00.000000 1\n"
                    "X:Act 2024-02-29 10:00:01.000000 2\n");
  EXPECT_EQ(read_camonitor(leap, o).rows(), 2u);
}

TEST(RecordingErrors, BadMapSyntax) {
  EXPECT_THROW(parse_column_map("x_cmd"), RecordingError);
  EXPECT_THROW(parse_column_map("speed=Feed"), RecordingError);
  EXPECT_THROW(parse_column_map("x_cmd=A,x_cmd=B"), RecordingError);
  EXPECT_THROW(parse_column_map("t=@index*0"), RecordingError);
  EXPECT_THROW(parse_column_map("t=@index*-1"), RecordingError);
  EXPECT_THROW(parse_column_map("t=@row*0.1"), RecordingError);
  EXPECT_THROW(parse_column_map("x_cmd="), RecordingError);
  // A '*' not followed by a number is part of the column name.
  EXPECT_EQ(parse_column_map("x_cmd=a*b").at("x_cmd").column, "a*b");
  EXPECT_EQ(parse_column_map("t=@index").at("t").scale, 1.0);
}

const char* kUmichMap =
    "t=@index*0.1,x_cmd=X1_CommandPosition,x_act=X1_ActualPosition,"
    "y_cmd=Y1_CommandPosition,y_act=Y1_ActualPosition,z_cmd=Z1_CommandPosition,"
    "z_act=Z1_ActualPosition,line=M1_sequence_number,feed=M1_CURRENT_FEEDRATE";

TEST(RecordingUmich, Experiment01ThroughMap) {
  RecordingOptions o;
  o.map = parse_column_map(kUmichMap);
  o.required = {"x_cmd", "y_cmd", "z_cmd"};
  auto rec = read_recording(test::data_dir() / "umich_cnc_mill" / "experiment_01.csv", o);
  ASSERT_EQ(rec.rows(), 1055u);
  EXPECT_EQ(rec.columns.size(), 48u);
  EXPECT_EQ(rec.channel("x_cmd").front(), 198.0);
  EXPECT_EQ(rec.channel("x_cmd").back(), 141.0);
  EXPECT_NEAR(rec.t_s.back(), 105.4, 1e-9);
  EXPECT_EQ(rec.channel("feed").front(), 50.0);
}

TEST(RecordingUmich, Experiment12HasCrOnlyLineEndings) {
  const auto file = test::data_dir() / "umich_cnc_mill" / "experiment_12.csv";
  ASSERT_NE(test::read_file(file).find('\r'), std::string::npos);
  ASSERT_EQ(test::read_file(file).find('\n'), std::string::npos);
  RecordingOptions o;
  o.map = parse_column_map(kUmichMap);
  auto rec = read_recording(file, o);
  ASSERT_EQ(rec.rows(), 2276u);
  EXPECT_EQ(rec.channel("x_cmd").front(), 144.0);
  EXPECT_EQ(rec.channel("x_cmd").back(), 152.0);
  EXPECT_NEAR(rec.t_s.back(), 227.5, 1e-9);
}

}  // namespace
}  // namespace truecut::analysis
