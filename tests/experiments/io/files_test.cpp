// The file layer (experiments/io/files.hpp): inputs that are not regular files are refused
// before a byte is read (a FIFO, /dev/zero, a folder, an oversized file), and an OutputPlan
// refuses an output that is an input, a non-regular file, a duplicate, a file reposetwin did not
// make (unless forced), and a run folder's symlink that leads outside it. Each case is a few
// system calls on a scratch folder.
#include "experiments/io/files.hpp"

#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

fs::path scratch(const std::string& name) {
  const fs::path d =
      fs::temp_directory_path() / ("reposetwin_files_" + name + "." + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  return d;
}

void put(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The message of the InputError `f` throws; fails the test when it throws none.
template <class F>
std::string refusal(F&& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "not refused";
  return "";
}

template <class F>
OutputRefusal refusal_kind(F&& f) {
  try {
    f();
  } catch (const OutputRefused& e) {
    return e.why();
  }
  ADD_FAILURE() << "not refused";
  return OutputRefusal::kIsInput;
}

TEST(InputFile, AFifoADeviceAFolderAndAnOversizedFileAreRefusedBeforeReading) {
  const fs::path d = scratch("inputs");
  ASSERT_EQ(::mkfifo((d / "pipe").c_str(), 0600), 0);
  // A reader that opened the FIFO would wait for a writer forever: the test would hang.
  std::string m = refusal([&] { (void)read_file((d / "pipe").string()); });
  EXPECT_NE(m.find((d / "pipe").string()), std::string::npos) << m;
  EXPECT_NE(m.find("FIFO"), std::string::npos) << m;
  m = refusal([&] { (void)read_file("/dev/zero"); });
  EXPECT_NE(m.find("/dev/zero: is a character device"), std::string::npos) << m;
  m = refusal([&] { check_input_file("/dev/zero"); });
  EXPECT_NE(m.find("device"), std::string::npos) << m;
  m = refusal([&] { (void)read_file(d.string()); });
  EXPECT_NE(m.find("is a directory, not a file"), std::string::npos) << m;
  put(d / "big.txt", std::string(100, 'x'));
  m = refusal([&] { (void)read_file((d / "big.txt").string(), 99); });
  EXPECT_NE(m.find("100 bytes, above the 99"), std::string::npos) << m;
  m = refusal([&] { (void)read_file((d / "none.txt").string()); });
  EXPECT_NE(m.find("none.txt: does not exist"), std::string::npos) << m;
  EXPECT_EQ(read_file((d / "big.txt").string(), 100), std::string(100, 'x'));
  // A symlink to a regular file is that file.
  fs::create_symlink(d / "big.txt", d / "link.txt");
  EXPECT_EQ(read_file((d / "link.txt").string()).size(), 100u);
  fs::remove_all(d);
}

TEST(OutputFile, AFifoOrADeviceAtTheTargetIsNeverReplaced) {
  const fs::path d = scratch("nonregular");
  ASSERT_EQ(::mkfifo((d / "overlay.png").c_str(), 0600), 0);
  EXPECT_EQ(refusal_kind([&] { write_file_atomic((d / "overlay.png").string(), "x"); }),
            OutputRefusal::kNotRegular);
  struct stat st {};
  ASSERT_EQ(::lstat((d / "overlay.png").c_str(), &st), 0);
  EXPECT_TRUE(S_ISFIFO(st.st_mode)) << "the FIFO was replaced by a file";
  // /dev/full as a target: refused by what it is (root could rename over it). Checked by a
  // plan, which writes nothing, so a broken check cannot harm the machine.
  OutputPlan plan(true);
  plan.add_output("/dev/full", "--truth");
  const std::string m = refusal([&] { plan.check(); });
  EXPECT_NE(m.find("--truth /dev/full: is a character device"), std::string::npos) << m;
  // A symlink is not replaced either (nor is what it points at written).
  put(d / "theirs.txt", "theirs");
  fs::create_symlink(d / "theirs.txt", d / "link.txt");
  EXPECT_EQ(refusal_kind([&] { write_file_atomic((d / "link.txt").string(), "x"); }),
            OutputRefusal::kNotRegular);
  EXPECT_EQ(slurp(d / "theirs.txt"), "theirs");
  fs::remove_all(d);
}

TEST(OutputPlan, AnOutputThatIsAnInputIsRefusedByAnyNameEvenWithForce) {
  const fs::path d = scratch("is_input");
  put(d / "in.png", "photo");
  fs::create_symlink(d / "in.png", d / "alias.png");
  fs::create_hard_link(d / "in.png", d / "hard.png");
  for (const fs::path& out : {d / "in.png", d / "." / "in.png", d / "alias.png", d / "hard.png"}) {
    OutputPlan plan(true);
    plan.add_input((d / "in.png").string());
    plan.add_output(out.string(), "--overlay");
    const std::string m = refusal([&] { plan.check(); });
    EXPECT_NE(m.find("--overlay " + out.string() + ": is the input"), std::string::npos) << m;
  }
  EXPECT_EQ(slurp(d / "in.png"), "photo");
  fs::remove_all(d);
}

TEST(OutputPlan, TwoOutputsAtOneFileAreRefused) {
  const fs::path d = scratch("duplicate");
  OutputPlan plan;
  plan.add_output((d / "m.png").string(), "--overlay");
  plan.add_output((d / "sub" / ".." / "m.png").string(), "--top-overlay");
  const std::string m = refusal([&] { plan.check(); });
  EXPECT_NE(m.find("--top-overlay"), std::string::npos) << m;
  EXPECT_NE(m.find("is also --overlay"), std::string::npos) << m;
  fs::remove_all(d);
}

TEST(OutputPlan, AFileReposetwinDidNotMakeIsKeptWithoutForce) {
  const fs::path d = scratch("not_made");
  const std::string theirs = (d / "index.html").string();
  put(theirs, "<p>my page</p>");
  {
    OutputPlan plan;
    plan.add_output(theirs, "--out");
    EXPECT_EQ(refusal_kind([&] { plan.check(); }), OutputRefusal::kNotMade);
    EXPECT_EQ(slurp(theirs), "<p>my page</p>");
  }
  {
    OutputPlan forced(true);
    forced.add_output(theirs, "--out");
    forced.check();
    forced.write(theirs, "ours 1");
  }
  // Made by us now: replaced again without --force.
  EXPECT_TRUE(made_by_us(theirs));
  {
    OutputPlan again;
    again.add_output(theirs);
    again.check();
    again.write(theirs, "ours 2");
    EXPECT_EQ(slurp(theirs), "ours 2");
  }
  // Edited by the user since: theirs again.
  put(theirs, "<p>edited</p>");
  EXPECT_FALSE(made_by_us(theirs));
  OutputPlan edited;
  edited.add_output(theirs);
  EXPECT_EQ(refusal_kind([&] { edited.check(); }), OutputRefusal::kNotMade);
  fs::remove_all(d);
}

TEST(RunFolderLinks, ALinkLeadingOutsideIsRefusedAndOneInsideIsNot) {
  const fs::path d = scratch("links");
  fs::create_directories(d / "run" / "frames");
  fs::create_directories(d / "elsewhere");
  put(d / "elsewhere" / "side_az000.png", "someone's photo");
  fs::create_directory_symlink("frames", d / "run" / "inside");
  refuse_escaping_links((d / "run").string());  // inside: fine
  fs::create_directory_symlink(d / "elsewhere", d / "run" / "images");
  const std::string m = refusal([&] { refuse_escaping_links((d / "run").string()); });
  EXPECT_NE(m.find((d / "run" / "images").string() + ": is a symbolic link leading outside"),
            std::string::npos)
      << m;
  fs::remove(d / "run" / "images");
  fs::create_symlink("../../elsewhere/side_az000.png", d / "run" / "frames" / "f.png");
  EXPECT_EQ(refusal_kind([&] { refuse_escaping_links((d / "run").string()); }),
            OutputRefusal::kEscapesFolder);
  fs::remove_all(d);
}

}  // namespace
}  // namespace reposetwin::experiments
