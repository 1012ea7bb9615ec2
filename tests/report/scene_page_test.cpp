// Scene pages: a hand-made scene (a table plane and two boxes above it) gives a page with the
// frame, one outline and one text label per object, the objects' pictures and the vote's next
// best classes; the index links the pages; bad input throws naming the counts.

#include "esf/report/scene_page.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "esf/core/error.hpp"

namespace fs = std::filesystem;

namespace {

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (std::size_t at = text.find(what); at != std::string::npos; at = text.find(what, at + 1))
        ++n;
    return n;
}

/// A table 2 m in front of the camera (plane z = 2, normal towards the camera) and two
/// 10 cm squares of points 20 cm above it, left and right of the optical axis.
struct Fixture {
    esf::PointCloud cloud;
    esf::SceneRecognition scene;

    Fixture() {
        for (int j = -20; j <= 20; ++j)
            for (int i = -30; i <= 30; ++i)
                cloud.points.emplace_back(0.02f * static_cast<float>(i),
                                          0.02f * static_cast<float>(j), 2.0f);
        scene.plane_found = true;
        scene.plane.normal = {0.0f, 0.0f, -1.0f};
        scene.plane.d = 2.0f;  // height = 2 - z
        scene.message = "2 objects above the plane";
        for (int o = 0; o < 2; ++o) {
            esf::RecognizedObject object;
            const float x0 = o == 0 ? -0.3f : 0.2f;
            for (int j = 0; j <= 10; ++j)
                for (int i = 0; i <= 10; ++i) {
                    object.cluster.points.emplace_back(x0 + 0.01f * static_cast<float>(i),
                                                       0.01f * static_cast<float>(j), 1.8f);
                    cloud.points.push_back(object.cluster.points.back());
                }
            object.classification.class_name = o == 0 ? "mug" : "tetra_pak";
            object.classification.confidence = 0.75;
            object.classification.best_model = o == 0 ? "mug_3" : "pak<1>";
            object.classification.best_view = 7;
            object.classification.best_distance = 0.125;
            object.classification.votes = {{object.classification.class_name, -1, 3, 0.4},
                                           {"bowl", -1, 1, 0.2}};
            scene.objects.push_back(std::move(object));
        }
        cloud.width = static_cast<std::uint32_t>(cloud.points.size());
    }
};

TEST(ScenePage, FrameOutlinesAndLabelsEveryObject) {
    const Fixture f;
    std::vector<esf::MatchedView> views(2);
    views[0].points = {{0.0f, 0.0f, 1.0f}, {0.01f, 0.0f, 1.0f}, {0.0f, 0.01f, 1.0f}};
    views[1].note = "no mesh for pak";
    const std::string html = esf::scene_page_html("scenes/table.pcd", f.cloud, f.scene, views);
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("</html>"), std::string::npos);
    EXPECT_EQ(count(html, "<image "), 1u);   // the frame
    EXPECT_EQ(count(html, "<polygon"), 2u);  // one outline per object
    EXPECT_NE(html.find(">0 mug 0.75</text>"), std::string::npos);
    EXPECT_NE(html.find(">1 tetra_pak 0.75</text>"), std::string::npos);
    EXPECT_NE(html.find("pak&lt;1&gt;"), std::string::npos);  // escaped
    EXPECT_EQ(html.find("pak<1>"), std::string::npos);
    EXPECT_NE(html.find("bowl (1)"), std::string::npos);  // the next best class
    EXPECT_NE(html.find("no mesh for pak"), std::string::npos);
    // Frame + two objects + the one drawn view, all embedded.
    EXPECT_EQ(count(html, "data:image/png;base64,"), 4u);
    EXPECT_EQ(html.find("http://"), html.find("http://www.w3.org/2000/svg"));  // no link out
}

TEST(ScenePage, OutlinesLieOnTheirObjectsSide) {
    // Object 0 is left of the optical axis, object 1 right of it: the outline of 0 lies in
    // the left half of the 480-pixel frame, that of 1 in the right half.
    const Fixture f;
    const std::string html = esf::scene_page_html("table.pcd", f.cloud, f.scene, {});
    std::vector<std::vector<double>> xs;
    for (std::size_t at = html.find("<polygon"); at != std::string::npos;
         at = html.find("<polygon", at + 1)) {
        const std::size_t from = html.find("points=\"", at) + 8, to = html.find('"', from);
        std::istringstream points(html.substr(from, to - from));
        std::vector<double> x;
        std::string pair;
        while (points >> pair) x.push_back(std::stod(pair.substr(0, pair.find(','))));
        ASSERT_GE(x.size(), 3u);
        xs.push_back(x);
    }
    ASSERT_EQ(xs.size(), 2u);
    for (double x : xs[0]) EXPECT_LT(x, 240.0);
    for (double x : xs[1]) EXPECT_GT(x, 240.0);
}

TEST(ScenePage, AFittedModelIsOutlinedDashedOverItsObject) {
    // Object 0's fitted model: a square a little larger than the object, at the same place.
    const Fixture f;
    std::vector<esf::MatchedView> views(2);
    for (int j = -1; j <= 11; ++j)
        for (int i = -1; i <= 11; ++i)
            views[0].points.emplace_back(-0.3f + 0.01f * static_cast<float>(i),
                                         0.01f * static_cast<float>(j), 1.8f);
    views[0].posed = true;
    views[1].points = {{0.0f, 0.0f, 1.0f}, {0.01f, 0.0f, 1.0f}, {0.0f, 0.01f, 1.0f}};
    const std::string html = esf::scene_page_html("table.pcd", f.cloud, f.scene, views);
    EXPECT_EQ(count(html, "<polygon"), 3u);  // two objects, one fitted model
    EXPECT_EQ(count(html, "stroke-dasharray"), 1u);
    EXPECT_NE(html.find("0 mug 0.75: the fitted model"), std::string::npos);
    const std::size_t at = html.find("<polygon class=\"fit\"");
    ASSERT_NE(at, std::string::npos);
    const std::size_t from = html.find("points=\"", at) + 8, to = html.find('"', from);
    std::istringstream points(html.substr(from, to - from));
    std::string pair;
    int corners = 0;
    while (points >> pair) {
        EXPECT_LT(std::stod(pair.substr(0, pair.find(','))), 240.0) << pair;  // left, as object 0
        ++corners;
    }
    EXPECT_GE(corners, 3);
    // Not posed (a training view in its own camera frame): no outline over the frame.
    views[0].posed = false;
    EXPECT_EQ(count(esf::scene_page_html("table.pcd", f.cloud, f.scene, views), "<polygon"), 2u);
}

TEST(ScenePage, IndexLinksPagesAndListsFailures) {
    std::vector<esf::ScenePageLink> links(2);
    links[0] = {"scene_000_a.html", "a.pcd", "1 object above the plane", {"mug"}, ""};
    links[1] = {"", "b.pcd", "", {}, "b.pcd: no such file"};
    const std::string html = esf::scene_index_html(links, "scenes");
    EXPECT_NE(html.find("<a href=\"scene_000_a.html\">a.pcd</a>"), std::string::npos);
    EXPECT_NE(html.find("b.pcd: no such file"), std::string::npos);
    EXPECT_EQ(count(html, "<a href="), 1u);
}

TEST(ScenePage, BadInputThrows) {
    const Fixture f;
    const std::vector<esf::MatchedView> one(1);
    try {
        esf::scene_page_html("t.pcd", f.cloud, f.scene, one);
        FAIL() << "no exception";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("1 matched views for 2 objects"), std::string::npos)
            << e.what();
    }
    const fs::path dir =
        fs::temp_directory_path() / ("esf_scene_page_test_" + std::to_string(::getpid()));
    fs::create_directories(dir);
    std::ofstream(dir / "file") << "x";
    try {
        esf::write_page((dir / "file" / "sub").string(), "index.html", "x");
        FAIL() << "no exception";
    } catch (const esf::IoError& e) {
        EXPECT_EQ(std::string(e.what()).rfind((dir / "file" / "sub").string(), 0), 0u) << e.what();
    }
    EXPECT_EQ(esf::write_page(dir.string(), "p.html", "<p>"), (dir / "p.html").string());
    std::ifstream in(dir / "p.html");
    std::string text;
    std::getline(in, text);
    EXPECT_EQ(text, "<p>");
    fs::remove_all(dir);
}

}  // namespace
