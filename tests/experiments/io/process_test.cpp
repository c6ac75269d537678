// The process layer (experiments/io/process.hpp): a program starts from an argument vector in
// the folder it is given, no word is parsed by a shell, and how it ended is a typed result; a
// failure names the program and the file.
#include "experiments/io/process.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

namespace reposetwin::experiments {
namespace {
namespace fs = std::filesystem;

TEST(Process, ArgumentsAndTheFolderReachTheProgramUnparsed) {
  const fs::path d = fs::temp_directory_path() /
                     ("reposetwin_process_O'Brien; $(touch pwned) `touch pwned2`\n\u00c5." +
                      std::to_string(::getpid()));
  fs::remove_all(d);
  fs::create_directories(d);
  ProgramCall call;
  // printf writes its arguments as given; pwd names the folder the spawn entered.
  call.argv = {"sh", "-c", "pwd; printf '%s\\n' \"$1\"", "sh", "a'b; $(touch pwned3)"};
  call.working_dir = d;
  call.log = d / "log.txt";
  const ProgramResult r = run_program(call);
  EXPECT_TRUE(r.ok()) << describe(r);
  std::ifstream in(call.log);
  const std::string text(std::istreambuf_iterator<char>(in), {});
  EXPECT_EQ(text, d.string() + "\na'b; $(touch pwned3)\n");
  for (const char* p : {"pwned", "pwned2", "pwned3"}) {
    EXPECT_FALSE(fs::exists(d / p)) << p;
    EXPECT_FALSE(fs::exists(p)) << p;
  }
  fs::remove_all(d);
}

TEST(Process, HowAProgramEndedIsTyped) {
  ProgramCall call;
  call.argv = {"sh", "-c", "exit 3"};
  ProgramResult r = run_program(call);
  EXPECT_EQ(r.status, ProgramStatus::kExited);
  EXPECT_EQ(r.code, 3);
  call.argv = {"sh", "-c", "kill -9 $$"};
  r = run_program(call);
  EXPECT_EQ(r.status, ProgramStatus::kSignaled);
  EXPECT_EQ(r.code, 9);
  call.argv = {"reposetwin-no-such-program"};
  r = run_program(call);
  EXPECT_EQ(r.status, ProgramStatus::kNotStarted);
  call.argv = {"true"};
  call.working_dir = "/nonexistent/folder";
  r = run_program(call);
  EXPECT_EQ(r.status, ProgramStatus::kNotStarted);
}

TEST(Process, AFailureNamesTheProgramAndTheFile) {
  ProgramCall call;
  call.argv = {"reposetwin-no-such-program", "plot.gp"};
  try {
    run_program_checked(call, "report/angles.gp");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("reposetwin-no-such-program (report/angles.gp): could not be started"),
              std::string::npos)
        << m;
    EXPECT_NE(m.find("installed"), std::string::npos) << m;
  }
  call.argv = {"false"};
  try {
    run_program_checked(call, "x.gp");
    FAIL() << "no error";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("false (x.gp): exited with status 1"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace reposetwin::experiments
