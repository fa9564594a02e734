// Writing a file whole or not at all: every output file of aarad (mesh.ply, the images, report.json, the OBJ/MTL
// export) goes through write_file_atomically, so a reader never sees a half-written file.
#pragma once

#include <filesystem>
#include <functional>
#include <string_view>

namespace aarad {

// Writes `path` whole or not at all. `write` receives a temporary path in the same directory as `path`,
// `.NAME.tmpPID-K.EXT` (NAME and EXT the stem and extension of `path`, PID the process id, K a counter of this
// process, so no two writes share a temporary), and must write the whole file there or throw. The temporary
// is then renamed to `path` (atomic within one file system). On failure the temporary file is removed and the
// exception propagates; a failed rename throws aarad::Error naming both paths.
void write_file_atomically(const std::filesystem::path& path,
                           const std::function<void(const std::filesystem::path& temporary)>& write);

// Writes `bytes` to `path` whole or not at all (write_file_atomically); a failed write, a full disk included, throws
// aarad::Error naming `path` and the reason.
void write_bytes_atomically(const std::filesystem::path& path, std::string_view bytes);

}  // namespace aarad
