// The meshlight binary: bad input gets file:line, a non-zero exit and no
// output file; good input writes what it says.
#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <string>

namespace fs = std::filesystem;

namespace {

struct CommandResult {
    int status;
    std::string output;  // stdout and stderr
};

CommandResult run(const std::string& args) {
    const std::string cmd = std::string(MESHLIGHT_BINARY) + " " + args + " 2>&1";
    CommandResult r{-1, {}};
    FILE* p = popen(cmd.c_str(), "r");
    if (!p) return r;
    std::array<char, 4096> buf;
    size_t n;
    while ((n = fread(buf.data(), 1, buf.size(), p)) > 0) r.output.append(buf.data(), n);
    const int s = pclose(p);
    r.status = WIFEXITED(s) ? WEXITSTATUS(s) : -1;
    return r;
}

class Cli : public ::testing::Test {
protected:
    void SetUp() override {
        dir = fs::temp_directory_path() / ("meshlight_cli_" + std::to_string(::getpid()) + "_" +
                                           ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::create_directories(dir);
    }
    void TearDown() override { fs::remove_all(dir); }
    std::string path(const std::string& name) const { return (dir / name).string(); }
    void write(const std::string& name, const std::string& text) const { std::ofstream(path(name)) << text; }
    // No file other than the inputs the test wrote.
    size_t files() const {
        size_t n = 0;
        for (auto& e : fs::directory_iterator(dir)) n += e.is_regular_file();
        return n;
    }
    fs::path dir;
};

const char* kQuadMtl = "newmtl lamp\nKd 0 0 0\nKe 5 5 5\nnewmtl white\nKd 0.5 0.5 0.5\n";
const char* kQuadObj =
    "mtllib scene.mtl\n"
    "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n"
    "v -0.2 2 -0.2\nv 0.2 2 -0.2\nv 0.2 2 0.2\nv -0.2 2 0.2\n"
    "usemtl white\nf 1 4 3 2\n"
    "usemtl lamp\nf 5 6 7 8\n";

}  // namespace

TEST_F(Cli, UnknownOptionIsAnErrorWithNoOutput) {
    const CommandResult r = run("render cornell --out " + path("x.png") + " --frobnicate 3");
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("unknown option '--frobnicate'"), std::string::npos) << r.output;
    EXPECT_EQ(files(), 0u);
}

TEST_F(Cli, UnknownCommandAndBadValues) {
    EXPECT_EQ(run("paint cornell").status, 2);
    const CommandResult bits = run("render cornell --bits 3 --out " + path("x.png"));
    EXPECT_EQ(bits.status, 2);
    EXPECT_NE(bits.output.find("bits per pixel 3"), std::string::npos) << bits.output;
    const CommandResult ext = run("render cornell --out " + path("x.jpg"));
    EXPECT_EQ(ext.status, 2);
    EXPECT_NE(ext.output.find("unsupported output format"), std::string::npos) << ext.output;
    const CommandResult width = run("render cornell --width abc --out " + path("x.png"));
    EXPECT_EQ(width.status, 2);
    EXPECT_EQ(files(), 0u);
}

TEST_F(Cli, MalformedObjNamesFileAndLine) {
    write("scene.mtl", kQuadMtl);
    write("bad.obj", "mtllib scene.mtl\nv 0 0 0\nv 1 nan 0\nv 0 0 1\nf 1 2 3\n");
    const CommandResult r = run("render " + path("bad.obj") + " --out " + path("out.png"));
    EXPECT_EQ(r.status, 2);
    EXPECT_NE(r.output.find("bad.obj:3:"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("out.png")));

    write("range.obj", "v 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 7\n");
    const CommandResult r2 = run("render " + path("range.obj") + " --out " + path("out.png"));
    EXPECT_EQ(r2.status, 2);
    EXPECT_NE(r2.output.find("range.obj:4:"), std::string::npos) << r2.output;

    write("nomtl.obj", "mtllib missing.mtl\nv 0 0 0\nv 1 0 0\nv 0 0 1\nf 1 2 3\n");
    const CommandResult r3 = run("render " + path("nomtl.obj") + " --out " + path("out.png"));
    EXPECT_EQ(r3.status, 2);
    EXPECT_NE(r3.output.find("nomtl.obj:1:"), std::string::npos) << r3.output;
    EXPECT_FALSE(fs::exists(path("out.png")));
}

TEST_F(Cli, RenderWritesTheImage) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    const CommandResult r = run("render " + path("scene.obj") + " --width 32 --height 24 --cache-edge 0.1 --out " + path("a.exr"));
    ASSERT_EQ(r.status, 0) << r.output;
    EXPECT_TRUE(fs::exists(path("a.exr")));
    EXPECT_NE(r.output.find("plan:"), std::string::npos);
    EXPECT_EQ(files(), 3u);  // obj, mtl, exr: no temporary left behind
}

TEST_F(Cli, ProbeAgreesWithExactAndRejectsBadPoints) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    write("points.csv", "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n0.5,0,0.3,0,1,0\n");
    const CommandResult exact = run("probe " + path("scene.obj") + " --points " + path("points.csv") + " --method exact --out " +
                          path("exact.csv"));
    ASSERT_EQ(exact.status, 0) << exact.output;
    const CommandResult jit = run("probe " + path("scene.obj") + " --points " + path("points.csv") + " --out " + path("jit.csv"));
    ASSERT_EQ(jit.status, 0) << jit.output;
    auto column = [](const std::string& file, int row, const std::string& name) {
        std::ifstream in(file);
        std::string line, header;
        std::getline(in, header);
        for (int i = 0; i <= row; ++i) std::getline(in, line);
        auto split = [](const std::string& s) {
            std::vector<std::string> v;
            size_t a = 0, b;
            while ((b = s.find(',', a)) != std::string::npos) { v.push_back(s.substr(a, b - a)); a = b + 1; }
            v.push_back(s.substr(a));
            return v;
        };
        const auto h = split(header), c = split(line);
        for (size_t i = 0; i < h.size(); ++i)
            if (h[i] == name) return std::stod(c[i]);
        return -1.0;
    };
    for (int row = 0; row < 2; ++row) {
        const double e = column(path("exact.csv"), row, "E_r");
        ASSERT_GT(e, 0);
        // Nothing occludes this lamp: the cv estimator is Lambert's value.
        EXPECT_NEAR(column(path("jit.csv"), row, "E_r"), e, 1e-6 * e);
    }

    write("bad.csv", "x,y,z,nx,ny,nz\n0,0,0,0,1,0\n1,2,inf,0,1,0\n");
    const CommandResult bad = run("probe " + path("scene.obj") + " --points " + path("bad.csv") + " --out " + path("o.csv"));
    EXPECT_EQ(bad.status, 2);
    EXPECT_NE(bad.output.find("bad.csv:3:"), std::string::npos) << bad.output;
    EXPECT_FALSE(fs::exists(path("o.csv")));
}

TEST_F(Cli, ProgressiveRenderLogsSnapshotsAndResumesFromItsCache) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    const std::string common = path("scene.obj") + " --width 24 --height 24 --supersample 1 --cache-edge 0.25";
    // A sample budget: the run repeats exactly whatever the machine's speed.
    CommandResult r = run("render " + common + " --samples 400 --every 0.01 --log " + path("log.csv") +
                          " --snapshots " + path("snaps") + " --cache " + path("scene.mlc") + " --out " +
                          path("a.exr"));
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_TRUE(fs::exists(path("a.exr")));
    EXPECT_TRUE(fs::exists(path("scene.mlc")));
    std::ifstream log(path("log.csv"));
    std::string header, row;
    std::getline(log, header);
    EXPECT_EQ(0u, header.find("seconds,frame,rounds,vertices,samples,estimated_error")) << header;
    size_t rows = 0;
    while (std::getline(log, row)) ++rows;
    EXPECT_GE(rows, 1u);  // at least the final row
    // Resuming: the cache file is read back and refined further.
    r = run("render " + common + " --samples 800 --cache " + path("scene.mlc") + " --out " + path("b.exr"));
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_NE(r.output.find("resumed from"), std::string::npos) << r.output;
    // A corrupt cache file is refused before any output is written, and kept.
    write("bad.mlc", "MESHLIGHT-CACHE\nnot really");
    r = run("render " + common + " --samples 400 --cache " + path("bad.mlc") + " --out " + path("c.exr"));
    EXPECT_EQ(2, r.status) << r.output;
    EXPECT_NE(r.output.find("bad.mlc"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("c.exr")));
    EXPECT_TRUE(fs::exists(path("bad.mlc")));
}

TEST_F(Cli, WalkthroughWritesOneImagePerCameraAndRejectsBadPaths) {
    write("scene.mtl", kQuadMtl);
    write("scene.obj", kQuadObj);
    write("path.csv", "# px,py,pz,tx,ty,tz,ux,uy,uz,fov\n0,1,4,0,0,0,0,1,0,40\n1,1,4,0,0,0,0,1,0,40\n");
    const std::string common = path("scene.obj") + " --width 16 --height 16 --supersample 1 --cache-edge 0.25";
    CommandResult r = run("render " + common + " --samples 300 --camera-path " + path("path.csv") + " --out " +
                          path("view_##.png"));
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_TRUE(fs::exists(path("view_00.png")));
    EXPECT_TRUE(fs::exists(path("view_01.png")));
    // A pattern without #### would overwrite one file.
    r = run("render " + common + " --camera-path " + path("path.csv") + " --out " + path("view.png"));
    EXPECT_EQ(2, r.status) << r.output;
    // A bad line is named with its file and line.
    write("bad.csv", "0,1,4,0,0,0,0,1,0,40\n0,1,4,0,0,0,0,1,0\n");
    r = run("render " + common + " --camera-path " + path("bad.csv") + " --out " + path("v_#.png"));
    EXPECT_EQ(2, r.status) << r.output;
    EXPECT_NE(r.output.find("bad.csv:2"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(path("v_0.png")));
}

TEST_F(Cli, PlanPrintsWhatWouldBeSimulated) {
    const CommandResult r = run("plan cornell");
    ASSERT_EQ(0, r.status) << r.output;
    EXPECT_NE(r.output.find("light 'light'"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("specular: no pass"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("grid cache"), std::string::npos) << r.output;
}
