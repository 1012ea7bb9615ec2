#pragma once
// The database file's format: its SQLite settings, its tables and the checks of its header
// (database.cpp opens and reads it, database_connection.cpp creates and checks it).

#include <array>
#include <cstdint>
#include <string>

#include "esf/training/database.hpp"

namespace esf::detail {

inline constexpr std::int32_t kApplicationId = 0x45534631;  // "ESF1"
inline constexpr int kBusyTimeoutMs = 10000;
inline constexpr int kPoseFloats = 16;
// Writers use a write-ahead log: a commit appends to it and syncs it once (about 5 ms, where a
// rollback journal needs about 20 ms), and readers never block the writer. A writer that closes
// cleanly switches the file back to a rollback journal (checkpointing the log into it), so the
// database is one self-contained file that read-only opens never add files to. A writer that is
// killed leaves the log beside the file; the next open replays its committed transactions.
// 16 KiB pages hold six 2.5 KiB ESF rows (4 KiB pages hold one, wasting 40 % of the file).
inline constexpr const char* kWriterPragmas =
    "PRAGMA journal_mode = WAL; PRAGMA synchronous = FULL;";
inline constexpr const char* kPageSize = "PRAGMA page_size = 16384";

inline constexpr const char* kSchema = R"sql(
CREATE TABLE settings(
    key TEXT PRIMARY KEY NOT NULL,
    value NOT NULL);
CREATE TABLE categories(
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE);
CREATE TABLE models(
    id INTEGER PRIMARY KEY,
    category_id INTEGER NOT NULL REFERENCES categories(id),
    name TEXT NOT NULL,
    file TEXT NOT NULL,
    grp TEXT NOT NULL,
    scale REAL NOT NULL,
    status TEXT NOT NULL CHECK(status IN ('complete', 'failed')),
    error TEXT NOT NULL DEFAULT '',
    UNIQUE(category_id, name));
CREATE TABLE views(
    id INTEGER PRIMARY KEY,
    model_id INTEGER NOT NULL REFERENCES models(id) ON DELETE CASCADE,
    view_index INTEGER NOT NULL,
    points INTEGER NOT NULL,
    pose BLOB NOT NULL,
    skipped INTEGER NOT NULL,
    skip_reason TEXT NOT NULL DEFAULT '',
    UNIQUE(model_id, view_index));
CREATE TABLE descriptor_kinds(
    id INTEGER PRIMARY KEY,
    name TEXT NOT NULL UNIQUE,
    version INTEGER NOT NULL,
    dimension INTEGER NOT NULL CHECK(dimension > 0));
CREATE TABLE descriptors(
    id INTEGER PRIMARY KEY,
    view_id INTEGER NOT NULL REFERENCES views(id) ON DELETE CASCADE,
    kind_id INTEGER NOT NULL REFERENCES descriptor_kinds(id),
    signature INTEGER NOT NULL,
    data BLOB NOT NULL,
    UNIQUE(view_id, kind_id, signature));
CREATE TABLE weights(
    kind_id INTEGER PRIMARY KEY REFERENCES descriptor_kinds(id),
    data BLOB NOT NULL);
)sql";

// What stored weights were learned on (Database::content_fingerprint). Not in kTables: files
// written before it existed lack it, and a writer adds it.
inline constexpr const char* kWeightsBasis = R"sql(
CREATE TABLE IF NOT EXISTS weights_basis(
    kind_id INTEGER PRIMARY KEY REFERENCES descriptor_kinds(id),
    fingerprint TEXT NOT NULL);
)sql";

// Each model's surface samples for verification (Database::model_surface): points and unit
// normals, float32 x y z each. Not in kTables: files written before it existed lack it (their
// models have no surface), and a writer adds it.
inline constexpr const char* kModelSurfaces = R"sql(
CREATE TABLE IF NOT EXISTS model_surfaces(
    model_id INTEGER PRIMARY KEY REFERENCES models(id) ON DELETE CASCADE,
    scale REAL NOT NULL,
    diameter REAL NOT NULL,
    points BLOB NOT NULL,
    normals BLOB NOT NULL);
)sql";

inline constexpr std::array<const char*, 7> kTables = {
    "settings", "categories", "models", "views", "descriptor_kinds", "descriptors", "weights"};

/// Reads the 100-byte SQLite header to give precise messages for files that are not SQLite
/// databases or were cut short (SQLite itself only notices when it reads a missing page).
/// Throws esf::IoError naming `path`; a missing or empty file is an error only for kRead.
void check_database_file_header(const std::string& path, OpenMode mode);

}  // namespace esf::detail
