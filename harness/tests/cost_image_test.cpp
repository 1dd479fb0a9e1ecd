// Cost images: the colour map runs dark to bright, and the per-pixel CSV holds exactly the
// counters given, so the analysis can redraw the heatmaps on a shared scale.
#include <gtest/gtest.h>

#include <algorithm>

#include "commands/cli.h"
#include "harness_test_util.h"
#include "util/cost_image.h"

namespace accelbench {
namespace {

using namespace testing_util;

double luminance(const std::array<uint8_t, 3>& c) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

TEST(CostImage, InfernoGetsBrighterAndClamps) {
    double previous = -1;
    for (int i = 0; i <= 100; ++i) {
        const double l = luminance(inferno(i / 100.0));
        EXPECT_GT(l, previous) << i;
        previous = l;
    }
    EXPECT_EQ(inferno(-1), inferno(0));
    EXPECT_EQ(inferno(7), inferno(1));
    EXPECT_LT(luminance(inferno(0)), 5);
    EXPECT_GT(luminance(inferno(1)), 240);
}

TEST(CostImage, WritesHeatmapsAndPerPixelValues) {
    TempDir dir("accelbench-cost-test-");
    std::vector<RayStats> px(6);
    for (size_t i = 0; i < px.size(); ++i) {
        px[i].node_visits = 10 * i;
        px[i].prim_tests = 100 - i;
    }
    const std::string prefix = (dir.path() / "bunny-bvh").string();
    const auto files = write_cost_images(px, 3, 2, prefix);
    ASSERT_EQ(files.size(), 3u);
    EXPECT_EQ(files[0], prefix + "-node_visits.png");
    EXPECT_TRUE(std::filesystem::file_size(files[0]) > 0);
    EXPECT_TRUE(std::filesystem::file_size(files[1]) > 0);
    EXPECT_EQ(read_file(files[2]),
              "x,y,node_visits,prim_tests\n0,0,0,100\n1,0,10,99\n2,0,20,98\n0,1,30,97\n1,1,40,96\n2,1,50,95\n");
    // The largest value is the top of the scale, zero its bottom.
    const Image img = heatmap({0, 25, 50, 0, 0, 50}, 3, 2, 50);
    EXPECT_EQ(img.rgb[0], inferno(0)[0]);
    EXPECT_EQ(img.rgb[6], inferno(1)[0]);
    EXPECT_EQ(img.rgb[7], inferno(1)[1]);
}

// `accelbench render --cost-out`: one CSV row per pixel, and Embree (no counters) refused.
TEST(CostImage, RenderCommandWritesThem) {
    TempDir dir("accelbench-cost-render-");
    const std::string prefix = (dir.path() / "soup-lbvh").string();
    std::vector<std::string> args = {
        "--model", "procedural:soup,triangles=300", "--accel", "lbvh", "--width", "16", "--height", "12", "--cost-out",
        prefix};
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    ASSERT_EQ(render_command(int(argv.size()), argv.data()), 0);
    const std::string csv = read_file(prefix + "-cost.csv");
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 1 + 16 * 12);
    EXPECT_TRUE(std::filesystem::exists(prefix + "-node_visits.png"));
    args[3] = "embree";
    argv.clear();
    for (auto& a : args) argv.push_back(a.data());
    EXPECT_EQ(render_command(int(argv.size()), argv.data()), 2);
}

// A parameter given twice in --model is refused naming both values, not resolved silently.
TEST(CostImage, RenderModelWithARepeatedParameterIsRefused) {
    try {
        resolve_model("procedural:soup,triangles=5,triangles=6", registry(), RenderSettings{});
        ADD_FAILURE() << "a repeated parameter was accepted";
    } catch (const std::exception& e) {
        EXPECT_NE(std::string(e.what()).find("parameter 'triangles' is given twice (triangles=5, then triangles=6)"),
                  std::string::npos)
            << e.what();
    }
}

// The render command's numbers follow the config's one rule: --width 010 is not read as 10.
TEST(CostImage, RenderFlagsRefuseNumbersYamlReadersDisagreeOn) {
    for (const char* written : {"010", "0x10"}) {
        std::vector<std::string> args = {
            "--model", "procedural:soup,triangles=30", "--accel", "bvh", "--width", written, "--height", "8"};
        std::vector<char*> argv;
        for (auto& a : args) argv.push_back(a.data());
        ::testing::internal::CaptureStderr();
        EXPECT_EQ(render_command(int(argv.size()), argv.data()), 2) << written;
        const std::string err = ::testing::internal::GetCapturedStderr();
        EXPECT_NE(err.find(std::string("--width: '") + written + "'"), std::string::npos) << err;
    }
}

}  // namespace
}  // namespace accelbench
