// The master's own film files (task results, checkpoints): written atomically through a temporary file
// and a rename, with an XXH3-64 checksum in a trailer, so that a file that was truncated, overwritten or
// damaged on disk is recognised when it is read back. Tasks are reproducible: what such a file held is
// rendered again rather than merged wrong or failing the job (merger.cpp, job_lifecycle.cpp).
#pragma once
#include <string>
#include <string_view>

#include "storage_error.h"

namespace pf::master {

// Writes `data` and its checksum to `path`; a reader (or a restarted master) sees either nothing or the
// whole file. With `durable` the data reaches the disk before the rename, for files that committed rows
// will name. Throws StorageError with the system's reason (e.g. "No space left on device").
void writeFilmFile(const std::string &path, std::string_view data, bool durable);

// The data of a file written by writeFilmFile. Throws farm::FarmError naming the file when it cannot be
// read, is truncated or fails its checksum.
std::string readFilmFile(const std::string &path);

// Throws StorageError unless a file can be created, written and removed in `dir` (at start: a data
// directory that is read-only or full is reported at once, naming the directory and the reason).
void checkWritable(const std::string &dir);

}  // namespace pf::master
