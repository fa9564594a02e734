// Whole-or-nothing file writing (see atomic_file.h): a temporary name in the destination's directory, then
// rename(2), which replaces the destination atomically on POSIX file systems.
#include "aarad/core/atomic_file.h"

#include "aarad/core/error.h"

#include <atomic>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <cstdint>
#include <string>
#include <system_error>
#include <unistd.h>

namespace aarad {

void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& temporary)>& write) {
  namespace fs = std::filesystem;
  // The process id keeps two processes writing into one directory apart, the counter two writes of one process.
  static std::atomic<std::uint64_t> counter{0};
  // Appended piece by piece: "." + string trips GCC 12's -Wrestrict false positive (GCC bug 105329).
  std::string name = ".";
  name += path.stem().string();
  name += ".tmp" + std::to_string(::getpid()) + "-" + std::to_string(counter.fetch_add(1));
  name += path.extension().string();
  const fs::path temporary = path.parent_path() / name;
  try {
    write(temporary);
  } catch (...) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw;
  }
  std::error_code error;
  fs::rename(temporary, path, error);
  if (error) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    throw Error("cannot rename " + temporary.string() + " to " + path.string() + ": " + error.message());
  }
}

void write_bytes_atomically(const std::filesystem::path& path, std::string_view bytes) {
  write_file_atomically(path, [&](const std::filesystem::path& temporary) {
    errno = 0;
    std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    out.close();  // the last buffer is written here: a full disk shows now
    if (!out) {
      const std::string reason = errno != 0 ? std::strerror(errno) : "the write failed";
      throw Error("cannot write " + path.string() + ": " + reason + "; check that its folder is writable and has room");
    }
  });
}

}  // namespace aarad
