#include "training/database_fingerprint.hpp"

#include "core/fnv1a.hpp"
#include "core/number_text.hpp"
#include "training/sqlite_statement.hpp"

namespace esf::detail {

namespace {

/// A content fingerprint: FNV-1a over texts, each followed by a zero byte, as 16 hex digits.
class Fingerprint {
  public:
    /// Adds `text` and a zero byte, so that ("ab", "c") and ("a", "bc") differ.
    void add(const std::string& text) { hash_ = fnv1a_byte(fnv1a(text, hash_), 0); }
    std::string hex() const {
        static constexpr char kDigits[] = "0123456789abcdef";
        std::string out(16, '0');
        for (int i = 0; i < 16; ++i) out[15 - i] = kDigits[(hash_ >> (4 * i)) & 0xf];
        return out;
    }

  private:
    std::uint64_t hash_ = kFnv1aOffsetBasis;
};

}  // namespace

std::string content_fingerprint(sqlite3* db, const std::string& path, std::int64_t kind_id) {
    SqliteStatement s(db, path,
                      "SELECT c.name, m.name, m.scale,"
                      " (SELECT count(*) FROM descriptors d JOIN views v ON v.id = d.view_id"
                      "  WHERE v.model_id = m.id AND d.kind_id = ?)"
                      " FROM models m JOIN categories c ON c.id = m.category_id"
                      " WHERE m.status = 'complete' ORDER BY c.name, m.name");
    s.bind(1, kind_id);
    Fingerprint hash;
    while (s.step()) {
        hash.add(s.text(0));
        hash.add(s.text(1));
        hash.add(detail::significant_text(s.real(2), 17));
        hash.add(std::to_string(s.int64(3)));
    }
    return hash.hex();
}

}  // namespace esf::detail
