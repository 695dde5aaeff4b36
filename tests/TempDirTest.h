// A test fixture with a directory of its own: made empty before each test,
// removed with everything in it after, so a test can check exactly which
// files a command wrote (and that a refused command wrote none).
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <system_error>

namespace ml::test {

class TempDirTest : public ::testing::Test {
protected:
    // <temp>/meshlight_<suite>_<pid>_<test>: unique per test and per
    // process, so test binaries run in parallel (ctest -j) never share one.
    void SetUp() override {
        const ::testing::TestInfo& info = *::testing::UnitTest::GetInstance()->current_test_info();
        dir_ = std::filesystem::temp_directory_path() /
               (std::string("meshlight_") + info.test_suite_name() + "_" + std::to_string(::getpid()) + "_" +
                info.name());
        std::filesystem::remove_all(dir_);
        std::filesystem::create_directories(dir_);
    }
    // Quiet when SetUp was skipped (a derived SetUp may GTEST_SKIP first).
    void TearDown() override {
        std::error_code ignored;
        if (!dir_.empty()) std::filesystem::remove_all(dir_, ignored);
    }

    // The full path of `name` in the directory.
    std::string path(const std::string& name) const { return (dir_ / name).string(); }
    // Writes `text` to `name` in the directory; returns its full path.
    std::string write(const std::string& name, const std::string& text) const {
        std::ofstream(path(name)) << text;
        return path(name);
    }
    // How many regular files the directory holds (not counting subfolders'):
    // what the test wrote plus what the command under test left.
    size_t files() const {
        size_t n = 0;
        for (const auto& e : std::filesystem::directory_iterator(dir_)) n += e.is_regular_file();
        return n;
    }

private:
    std::filesystem::path dir_;
};

}  // namespace ml::test
