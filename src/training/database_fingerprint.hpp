#pragma once
// What a database's descriptors of one kind were computed from (Database::content_fingerprint):
// FNV-1a over the complete models' category, name, scale and descriptor count.

#include <sqlite3.h>

#include <cstdint>
#include <string>

namespace esf::detail {

/// The fingerprint of the descriptors of kind row `kind_id` in `db` (the file `path`), 16 hex
/// digits. Throws esf::IoError naming `path` when the database cannot be read.
std::string content_fingerprint(sqlite3* db, const std::string& path, std::int64_t kind_id);

}  // namespace esf::detail
