// File helpers: atomic writes (a crash never leaves a half-written output) and
// checked reads.
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

namespace semrec {

/// Writes `path` atomically: `write(tmp_path)` fills a temporary file in the
/// same folder, which is then renamed over `path`. Creates missing parent
/// folders. On any exception the temporary file is removed and `path` is left
/// untouched.
void WriteFileAtomic(
    const std::filesystem::path& path,
    const std::function<void(const std::filesystem::path& tmp_path)>& write);

/// Atomically writes `content` to `path`.
void WriteTextFileAtomic(const std::filesystem::path& path,
                         const std::string& content);

/// Whole file as bytes. Throws IoError naming the file when it is missing or
/// unreadable.
std::vector<unsigned char> ReadFileBytes(const std::filesystem::path& path);
std::string ReadTextFile(const std::filesystem::path& path);

/// Throws IoError unless `path` is an existing regular file (`what` describes
/// it in the message).
void RequireFile(const std::filesystem::path& path,
                 const std::string& what = "file");
/// Throws IoError unless `path` is an existing folder.
void RequireDirectory(const std::filesystem::path& path,
                      const std::string& what = "folder");

/// Throws IoError when `dir` exists and is not empty, unless `overwrite`: the
/// rule every command that writes an output folder follows.
void RequireEmptyOrOverwrite(const std::filesystem::path& dir, bool overwrite);

/// `path`'s extension, lower-cased (".PNG" -> ".png"; "" when none).
std::string LowerExtension(const std::filesystem::path& path);

/// The folder of the project's data files (label sets, model registry):
/// $SEMREC_DATA_DIR when set, else the `data/` folder of the source tree this
/// library was built from.
std::filesystem::path ProjectDataDir();

/// The model cache filled by scripts/setup: $SEMREC_MODELS when set, else
/// `.deps/models` in the source tree this library was built from.
std::filesystem::path DefaultModelDir();

}  // namespace semrec
