// The one file writer: a file is replaced whole or not at all; two writers of the same file at
// once both succeed and leave one of their contents; errors name the file and leave no
// temporary behind.

#include "core/atomic_file.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

#include "esf/core/error.hpp"

namespace {

namespace fs = std::filesystem;
using esf::detail::write_file_atomically;

class AtomicFile : public ::testing::Test {
  protected:
    void SetUp() override {
        const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = fs::temp_directory_path() /
               ("esf_atomic_file_test_" + std::to_string(::getpid()) + "_" + info->name());
        fs::remove_all(dir_);
        fs::create_directories(dir_);
    }
    void TearDown() override {
        std::error_code ec;
        fs::remove_all(dir_, ec);
    }

    std::vector<std::string> entries() const {
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(dir_)) names.push_back(e.path().filename());
        std::sort(names.begin(), names.end());
        return names;
    }

    fs::path dir_;
};

std::string read_file(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

std::string error_of(const auto& call) {
    try {
        call();
    } catch (const esf::IoError& e) {
        return e.what();
    }
    return {};
}

TEST_F(AtomicFile, WritesAndReplacesAFile) {
    const fs::path path = dir_ / "file.bin";
    const std::string first("first\0with a zero byte", 22);
    write_file_atomically(path, first);
    EXPECT_EQ(read_file(path), first);
    write_file_atomically(path, "second", 6);
    EXPECT_EQ(read_file(path), "second");
    write_file_atomically(path, [](std::ostream& out) { out << "third " << 3; });
    EXPECT_EQ(read_file(path), "third 3");
    write_file_atomically(path, std::string_view());
    EXPECT_EQ(read_file(path), "");
    EXPECT_EQ(entries(), std::vector<std::string>{"file.bin"});
}

TEST_F(AtomicFile, TwoWritersOfOneFileBothSucceedAndOneWholeContentRemains) {
    const fs::path path = dir_ / "shared.txt";
    const std::string a(1 << 20, 'a'), b(1 << 19, 'b');
    for (int round = 0; round < 20; ++round) {
        std::string error_a, error_b;
        std::thread writer_a([&] { error_a = error_of([&] { write_file_atomically(path, a); }); });
        std::thread writer_b([&] { error_b = error_of([&] { write_file_atomically(path, b); }); });
        writer_a.join();
        writer_b.join();
        EXPECT_EQ(error_a, "");
        EXPECT_EQ(error_b, "");
        const std::string content = read_file(path);
        EXPECT_TRUE(content == a || content == b)
            << "round " << round << ": " << content.size() << " bytes";
        EXPECT_EQ(entries(), std::vector<std::string>{"shared.txt"});
    }
}

TEST_F(AtomicFile, AFailedWriteLeavesTheOldFileAndNoTemporary) {
    const fs::path path = dir_ / "kept.txt";
    write_file_atomically(path, std::string_view("old content"));
    // The writer throws half way: the old file stays as it was.
    EXPECT_THROW(write_file_atomically(path,
                                       [](std::ostream& out) {
                                           out << "new content, cut short";
                                           throw std::runtime_error("stopped");
                                       }),
                 std::runtime_error);
    EXPECT_EQ(read_file(path), "old content");
    // A stream that fails is a write error naming the file.
    EXPECT_EQ(error_of([&] {
                  write_file_atomically(path, [](std::ostream& out) {
                      out << "partial";
                      out.setstate(std::ios::badbit);
                  });
              }),
              path.string() + ": write failed");
    EXPECT_EQ(read_file(path), "old content");
    EXPECT_EQ(entries(), std::vector<std::string>{"kept.txt"});
}

TEST_F(AtomicFile, ErrorsNameTheFile) {
    const fs::path nowhere = dir_ / "no" / "such" / "dir" / "file.txt";
    EXPECT_EQ(error_of([&] { write_file_atomically(nowhere, std::string_view("x")); }),
              nowhere.string() + ": cannot create temporary file: No such file or directory");
    // A directory in the way: the rename fails, the directory stays and no temporary is left.
    const fs::path taken = dir_ / "taken";
    fs::create_directory(taken);
    EXPECT_EQ(error_of([&] {
                  write_file_atomically(taken, std::string_view("x"));
              }).rfind(taken.string() + ": cannot replace the file: ", 0),
              0u);
    EXPECT_TRUE(fs::is_directory(taken));
    EXPECT_EQ(entries(), std::vector<std::string>{"taken"});
}

TEST_F(AtomicFile, NewFilesGetTheUsualPermissions) {
    const fs::path path = dir_ / "mode.txt";
    write_file_atomically(path, std::string_view("x"));
    const mode_t mask = ::umask(0);
    ::umask(mask);
    const auto expected = static_cast<fs::perms>(0666 & ~mask);
    EXPECT_EQ(fs::status(path).permissions() & fs::perms::all, expected);
}

}  // namespace
