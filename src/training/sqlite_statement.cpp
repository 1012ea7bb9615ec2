#include "training/sqlite_statement.hpp"

#include <cstring>

#include "esf/core/error.hpp"

namespace esf::detail {

std::vector<unsigned char> float_blob(std::span<const float> values) {
    std::vector<unsigned char> blob(values.size_bytes());
    if (!values.empty()) std::memcpy(blob.data(), values.data(), values.size_bytes());
    return blob;
}

SqliteStatement::SqliteStatement(sqlite3* db, const std::string& path, const char* sql)
    : db_(db), path_(&path) {
    if (sqlite3_prepare_v2(db, sql, -1, &stmt_, nullptr) != SQLITE_OK) fail();
}

SqliteStatement::~SqliteStatement() { sqlite3_finalize(stmt_); }

SqliteStatement& SqliteStatement::bind_blob(int i, std::span<const float> v) {
    const auto blob = float_blob(v);
    return check(
        sqlite3_bind_blob(stmt_, i, blob.data(), static_cast<int>(blob.size()), SQLITE_TRANSIENT));
}

bool SqliteStatement::step() {
    const int rc = sqlite3_step(stmt_);
    if (rc == SQLITE_ROW) return true;
    if (rc == SQLITE_DONE) return false;
    fail();
}

std::string SqliteStatement::text(int col) const {
    const auto* p = sqlite3_column_text(stmt_, col);
    return p ? std::string(reinterpret_cast<const char*>(p),
                           static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col)))
             : std::string();
}

void SqliteStatement::floats(int col, float* out, std::size_t count, const char* what) const {
    const void* p = sqlite3_column_blob(stmt_, col);
    const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col));
    if (bytes != count * sizeof(float))
        throw IoError(file_message(*path_, 0,
                                   std::string("corrupt database: ") + what + " holds " +
                                       std::to_string(bytes) + " bytes, expected " +
                                       std::to_string(count * sizeof(float))));
    if (count) std::memcpy(out, p, bytes);
}

std::vector<float> SqliteStatement::floats(int col) const {
    const auto bytes = static_cast<std::size_t>(sqlite3_column_bytes(stmt_, col));
    std::vector<float> out(bytes / sizeof(float));
    floats(col, out.data(), out.size(), "a float array");
    return out;
}

void SqliteStatement::fail() const { throw IoError(file_message(*path_, 0, sqlite3_errmsg(db_))); }

}  // namespace esf::detail
