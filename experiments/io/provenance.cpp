#include "experiments/io/provenance.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "experiments/io/input_error.hpp"

namespace reposetwin::experiments {

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

namespace {

// Writes all of `text` to `fd` and flushes it to the disk; false on any failure.
bool write_all_and_sync(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return ::fsync(fd) == 0;
}

// Makes a rename in `dir` durable: without it a crash can leave the old name after the new
// file's data reached the disk.
void sync_folder(const std::filesystem::path& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

}  // namespace

void write_file_atomic(const std::string& path, const std::string& text) {
  namespace fs = std::filesystem;
  const fs::path target(path);
  std::error_code ec;
  if (target.has_parent_path()) fs::create_directories(target.parent_path(), ec);
  const fs::path tmp =
      target.parent_path() / (target.filename().string() + ".tmp." + std::to_string(::getpid()));
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0)
    throw std::runtime_error(path + ": cannot open for writing (" + std::strerror(errno) + ")");
  const bool written = write_all_and_sync(fd, text);
  const int saved = errno;
  ::close(fd);
  if (!written) {
    fs::remove(tmp, ec);  // a full disk must not leave the temporary behind
    throw std::runtime_error(path + ": write failed (" + std::strerror(saved) + ")");
  }
  fs::rename(tmp, target, ec);
  if (ec) {
    const std::string why = ec.message();  // "Is a directory", "Permission denied", ...
    fs::remove(tmp, ec);
    throw std::runtime_error(path + ": cannot move the finished file into place (" + why + ")");
  }
  sync_folder(target.parent_path());
}

FolderLock::FolderLock(const std::string& dir, const std::string& name, const std::string& what) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec) throw std::runtime_error(dir + ": cannot make the folder (" + ec.message() + ")");
  const std::string p = (std::filesystem::path(dir) / name).string();
  fd_ = ::open(p.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
  if (fd_ < 0)
    throw std::runtime_error(p + ": cannot open the lock file (" + std::strerror(errno) +
                             "); is " + dir + " a folder this process may write?");
  if (::flock(fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(fd_);
    fd_ = -1;
    throw FolderBusy(dir + ": " + what + " is already running in this folder (" + p +
                     " is locked); wait for it or use another folder");
  }
}

FolderLock::~FolderLock() {
  if (fd_ >= 0) ::close(fd_);
}

void write_json_atomic(const std::string& path, const nlohmann::json& j) {
  write_file_atomic(path, j.dump(2) + "\n");
}

std::string read_file(const std::string& path, std::uintmax_t max_bytes) {
  // A directory opens as an empty stream on Linux: read as "", it would surface later as a
  // missing table or column instead of the real mistake. A FIFO blocks the open until someone
  // writes, and a device (/dev/zero) never ends: only a regular file of a bounded size is read.
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(st))
    throw std::runtime_error(path + ": is a directory, not a file");
  if (std::filesystem::exists(st) && !std::filesystem::is_regular_file(st))
    throw std::runtime_error(path + ": is not a regular file (a pipe, socket or device)");
  const std::uintmax_t size = std::filesystem::file_size(path, ec);
  if (!ec && size > max_bytes)
    throw std::runtime_error(path + ": is " + std::to_string(size) + " bytes, above the " +
                             std::to_string(max_bytes) + " this file may have");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open");
  std::string text;
  text.resize(static_cast<std::size_t>(ec ? 0 : size));
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (in.gcount() == static_cast<std::streamsize>(size) &&
      in.peek() != std::ifstream::traits_type::eof())
    throw std::runtime_error(path + ": grew while it was read");
  return text;
}

}  // namespace reposetwin::experiments
