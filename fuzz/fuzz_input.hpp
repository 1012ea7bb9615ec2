#pragma once
// Helpers shared by the fuzz targets: the input as a stream, or as a file in a private folder.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <fstream>
#include <string>
#include <string_view>

namespace esf::fuzz {

inline std::string_view bytes_of(const std::uint8_t* data, std::size_t size) {
    return {reinterpret_cast<const char*>(data), size};
}

/// A file named `name` in a folder private to this process, holding `bytes`; removed on exit.
class TempFile {
  public:
    TempFile(const std::string& name, std::string_view bytes) {
        char dir[] = "/tmp/esf_fuzz_XXXXXX";
        if (mkdtemp(dir) == nullptr) __builtin_trap();
        dir_ = dir;
        path_ = dir_ + "/" + name;
        std::ofstream out(path_, std::ios::binary);
        out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    }
    ~TempFile() {
        for (const char* suffix : {"", "-journal", "-wal", "-shm"})
            ::unlink((path_ + suffix).c_str());
        ::rmdir(dir_.c_str());
    }
    TempFile(const TempFile&) = delete;
    TempFile& operator=(const TempFile&) = delete;
    const std::string& path() const { return path_; }

  private:
    std::string dir_;
    std::string path_;
};

}  // namespace esf::fuzz
