#pragma once
// One writer of a database at a time: an exclusive flock() on the file, held until the writer
// closes. (SQLite's own locks last one transaction, so two trainings would interleave models
// and race to create the schema.) Readers take no lock and are never refused.

#include <string>

namespace esf::detail {

/// Opens `path` and takes the exclusive lock without waiting; returns the descriptor that holds
/// it (closing it releases the lock). Throws esf::IoError naming `path` when the file cannot be
/// opened or another writer holds the lock ("database is in use by another training").
int lock_database_for_writing(const std::string& path);

}  // namespace esf::detail
