#pragma once
// Write-to-temporary-then-rename, so a final name only ever holds a complete file; and the
// temporaries that killed processes left behind (findTemporaries), for batch --resume and
// aperture.distributed.
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace aperture {

/// A temporary path in the same directory as `finalPath` (".name.tmp-PID-N" followed by
/// `suffix`), so rename is atomic on the same filesystem. N counts up within the process.
/// `suffix` keeps an extension visible to writers that pick the format from the name
/// (".png").
std::string temporaryPathFor(const std::string& finalPath, const std::string& suffix = "");

/// The parts of a temporary file name made by temporaryPathFor.
struct TemporaryName {
  std::string finalName;      ///< NAME: the file name it is renamed to when complete
  long pid = 0;               ///< PID of the process that made it
  unsigned long counter = 0;  ///< N
  std::string suffix;         ///< what follows N: "" or an extension such as ".png"
};

/// Parses a file name (no directory) of the form ".NAME.tmp-PID-N" + suffix, where the suffix
/// is empty or starts with '.'; nothing for any other name. temporaryPathFor checks that its
/// names parse back, so the naming scheme has this one definition.
std::optional<TemporaryName> parseTemporaryName(const std::string& fileName);

/// Calls write(tmpPath), fsyncs the file, renames it over `finalPath`. If write throws or any
/// step fails, the temporary file is removed, `finalPath` is untouched, and Error is thrown
/// naming `finalPath` and the reason (e.g. "No space left on device"). The directory of
/// `finalPath` must exist. `suffix` is passed to temporaryPathFor.
void writeAtomically(const std::string& finalPath,
                     const std::function<void(const std::string& tmpPath)>& write,
                     const std::string& suffix = "");

/// Writes `text` to `finalPath` atomically.
void writeTextAtomically(const std::string& finalPath, const std::string& text);

/// Writes `size` bytes at `data` to `finalPath` atomically, checking every write (a full disk
/// is an Error, never a short file).
void writeBytesAtomically(const std::string& finalPath, const void* data, size_t size);

/// `size` bytes at `data`: one piece of a file written by writePiecesAtomically.
struct BytePiece {
  const void* data = nullptr;
  size_t size = 0;
};

/// Writes the pieces one after the other to `finalPath` atomically, each write checked, without
/// joining them in memory first (large arrays go to the file from where they are).
void writePiecesAtomically(const std::string& finalPath, const std::vector<BytePiece>& pieces);

/// True unless kill(pid, 0) says that no process `pid` exists (ESRCH); a PID that cannot be a
/// process (<= 0 or beyond pid_t) counts as dead.
bool processAlive(long pid);

/// A temporary file (".NAME.tmp-PID-N…", see parseTemporaryName) found beside an output.
struct TemporaryFile {
  std::string path;
  long pid = 0;
  bool alive = false;  ///< its process still exists
};

/// The temporaries of the files `finalPaths` (those whose NAME is one of them), searched in
/// each of their directories once; `alive` decides whether a PID's process still exists.
/// Other files, including temporaries of other names, are not listed.
std::vector<TemporaryFile> findTemporaries(const std::vector<std::string>& finalPaths,
                                           const std::function<bool(long)>& alive = processAlive);

}  // namespace aperture
