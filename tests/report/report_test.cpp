// Reports: the five files are written, report.json parses and holds the numbers, the PNG
// decodes with libpng to the expected size, the SVGs are well-formed enough, the HTML holds
// the per-class table and the inline images.

#include "esf/report/report.hpp"

#include <gtest/gtest.h>
#include <png.h>
#include <unistd.h>

#include <csetjmp>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "esf/core/error.hpp"
#include "esf/evaluation/evaluation.hpp"

namespace fs = std::filesystem;

namespace {

std::string read_text(const fs::path& path) {
    std::ifstream in(path, std::ios::binary);
    std::stringstream s;
    s << in.rdbuf();
    return s.str();
}

esf::EvaluationReport sample_report() {
    const std::vector<std::string> classes = {"mug", "tetra_pak", "bowl"};
    std::vector<esf::QueryOutcome> outcomes;
    auto add = [&](const std::string& truth, const std::vector<std::string>& neighbours) {
        esf::QueryOutcome o;
        o.file = "q" + std::to_string(outcomes.size()) + ".pcd";
        o.true_class = truth;
        for (const auto& n : neighbours) o.neighbours.push_back({n, 0.5});
        outcomes.push_back(o);
    };
    add("mug", {"mug", "bowl"});
    add("mug", {"bowl", "mug"});
    add("mug", {"mug"});
    add("tetra_pak", {"tetra_pak"});
    add("bowl", {"mug", "mug"});
    add("chair", {"mug"});
    esf::EvaluationReport r = esf::evaluate(outcomes, 2, classes);
    r.mode = "test set";
    r.test_set = "labels.csv";
    r.descriptor = "esf";
    r.describe_ms = 1.5;
    r.match_ms = 0.25;
    return r;
}

struct DecodedPng {
    png_uint_32 width = 0, height = 0;
    int bit_depth = 0, color_type = 0;
    bool ok = false;
};

void on_error(png_structp png, png_const_charp) { png_longjmp(png, 1); }

bool read_png_file(std::FILE* file, png_structp png, png_infop info, DecodedPng* out) {
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, file);
    png_read_info(png, info);
    png_get_IHDR(png, info, &out->width, &out->height, &out->bit_depth, &out->color_type, nullptr,
                 nullptr, nullptr);
    return true;
}

DecodedPng decode(const std::string& path) {
    DecodedPng out;
    std::FILE* file = std::fopen(path.c_str(), "rb");
    if (!file) return out;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, nullptr, on_error, nullptr);
    png_infop info = png_create_info_struct(png);
    out.ok = read_png_file(file, png, info, &out);
    if (out.ok) {
        // Decode every row too, so that a truncated or corrupt stream fails.
        std::vector<png_byte> row(png_get_rowbytes(png, info));
        struct Reader {
            static bool rows(png_structp p, png_infop i, png_bytep r, png_uint_32 h) {
                if (setjmp(png_jmpbuf(p))) return false;
                for (png_uint_32 y = 0; y < h; ++y) png_read_row(p, r, nullptr);
                png_read_end(p, i);
                return true;
            }
        };
        out.ok = Reader::rows(png, info, row.data(), out.height);
    }
    png_destroy_read_struct(&png, &info, nullptr);
    std::fclose(file);
    return out;
}

class ReportTest : public ::testing::Test {
  protected:
    void SetUp() override {
        dir_ = fs::temp_directory_path() /
               ("esf_report_test_" + std::to_string(::getpid()) + "_" +
                ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(dir_);
    }
    void TearDown() override { fs::remove_all(dir_); }
    fs::path dir_;
};

TEST_F(ReportTest, WritesAllFiles) {
    const esf::EvaluationReport r = sample_report();
    esf::ReportOptions options;
    options.title = "unit <test> & report";
    const esf::ReportFiles files = esf::write_report((dir_ / "a" / "b").string(), r, options);
    for (const std::string& f :
         {files.json, files.confusion_png, files.confusion_svg, files.rank_curves_svg, files.html})
        EXPECT_TRUE(fs::is_regular_file(f)) << f;
    EXPECT_EQ(fs::path(files.html).filename(), "index.html");
    // No temporary files are left behind.
    std::size_t entries = 0;
    for ([[maybe_unused]] const auto& e : fs::directory_iterator(dir_ / "a" / "b")) ++entries;
    EXPECT_EQ(entries, 5u);

    const nlohmann::json j = nlohmann::json::parse(read_text(files.json));
    EXPECT_EQ(j["title"], options.title);
    EXPECT_EQ(j["k"], 2);
    EXPECT_EQ(j["overall"]["samples"], 5);
    EXPECT_DOUBLE_EQ(j["overall"]["top1"].get<double>(), 3.0 / 5.0);
    EXPECT_DOUBLE_EQ(j["overall"]["top10"].get<double>(), 4.0 / 5.0);
    ASSERT_EQ(j["classes"].size(), 3u);
    EXPECT_EQ(j["classes"][0]["class"], "bowl");
    EXPECT_EQ(j["classes"][0]["confused_with"], "mug");
    EXPECT_EQ(j["classes"][0]["top10"], 0.0);
    EXPECT_EQ(j["confusion"]["rows"].size(), 3u);
    EXPECT_EQ(j["confusion"]["counts"][1][0], 2);  // mug -> mug, twice
    EXPECT_EQ(j["confusion"]["counts"][1][2], 1);  // mug -> bowl, once (columns as given)
    EXPECT_EQ(j["skipped"], 1);
    EXPECT_EQ(j["missing_classes"][0]["class"], "chair");
    EXPECT_EQ(j["queries"].size(), 5u);
    EXPECT_DOUBLE_EQ(j["timings"]["describe_ms"].get<double>(), 1.5);

    const DecodedPng png = decode(files.confusion_png);
    ASSERT_TRUE(png.ok);
    EXPECT_EQ(png.bit_depth, 8);
    EXPECT_EQ(png.color_type, PNG_COLOR_TYPE_RGB);
    EXPECT_GT(png.width, 100u);
    EXPECT_GT(png.height, 100u);

    const std::string svg = read_text(files.rank_curves_svg);
    EXPECT_EQ(svg.rfind("<svg xmlns=\"http://www.w3.org/2000/svg\"", 0), 0u);
    EXPECT_NE(svg.find("</svg>"), std::string::npos);
    EXPECT_NE(svg.find("tetra_pak"), std::string::npos);  // the legend
    EXPECT_NE(svg.find("unit &lt;test&gt; &amp; report"), std::string::npos);
    EXPECT_EQ(svg.find("<test>"), std::string::npos);
    const std::string confusion = read_text(files.confusion_svg);
    EXPECT_NE(confusion.find("mug -&gt; bowl: 1 (33.3 %)"), std::string::npos);

    const std::string html = read_text(files.html);
    EXPECT_EQ(html.rfind("<!DOCTYPE html>", 0), 0u);
    EXPECT_NE(html.find("<th>2-NN %</th>"), std::string::npos);
    EXPECT_NE(html.find("<td class=\"name\">mug</td><td>3</td><td>66.7</td><td>100.0</td>"
                        "<td class=\"name\">bowl (1)</td>"),
              std::string::npos)
        << html;
    // Both figures inline as SVG, their labels as text: no picture of text.
    EXPECT_NE(html.find("<svg"), std::string::npos);
    EXPECT_NE(html.find("mug -&gt; bowl: 1 (33.3 %)"), std::string::npos);
    EXPECT_EQ(html.find("data:image/png"), std::string::npos);
    EXPECT_EQ(html.find("Misclassified views"), std::string::npos);  // no gallery given
    EXPECT_NE(html.find("chair: 1"), std::string::npos);
}

TEST_F(ReportTest, GalleryShowsEachEntryWithItsPicturesAndDistances) {
    esf::ReportOptions options;
    esf::GalleryEntry e;
    e.file = "/data/bowl_3.pcd";
    e.true_class = "bowl";
    e.predicted = "mug";
    e.matched_view = "mug_1 #12";
    e.matched_distance = 0.25;
    e.true_view = "bowl_2 #4";
    e.true_distance = 0.3125;
    e.rank = 2;
    e.query = {"data:image/png;base64,AAAA", "query: bowl"};
    e.matched = {"data:image/png;base64,BBBB", "nearest: mug"};
    e.nearest_true = {"", "nearest bowl"};
    e.note = "bowl_2: mesh <missing>";
    options.gallery = {e};
    const std::string html = esf::report_html(sample_report(), options);
    EXPECT_NE(html.find("Misclassified views"), std::string::npos);
    EXPECT_NE(html.find("src=\"data:image/png;base64,AAAA\""), std::string::npos);
    EXPECT_NE(html.find("src=\"data:image/png;base64,BBBB\""), std::string::npos);
    EXPECT_NE(html.find("<div class=\"nopic\"></div><figcaption>nearest bowl"), std::string::npos);
    EXPECT_NE(html.find(">data/bowl_3.pcd<"), std::string::npos);  // folder and name
    EXPECT_EQ(html.find("/data/bowl_3.pcd"), std::string::npos);
    EXPECT_NE(html.find("mug_1 #12, distance 0.2500"), std::string::npos);
    EXPECT_NE(html.find("bowl_2 #4, distance 0.3125"), std::string::npos);
    EXPECT_NE(html.find("(rank 2)"), std::string::npos);
    EXPECT_NE(html.find("mesh &lt;missing&gt;"), std::string::npos);
}

TEST_F(ReportTest, OutputIsDeterministic) {
    const esf::EvaluationReport r = sample_report();
    EXPECT_EQ(esf::report_html(r), esf::report_html(r));
    EXPECT_EQ(esf::confusion_png(r), esf::confusion_png(r));
    esf::ReportOptions options;
    options.include_queries = false;
    EXPECT_FALSE(nlohmann::json::parse(esf::report_json(r, options)).contains("queries"));
}

TEST_F(ReportTest, EmptyAndLargeReportsRender) {
    const std::vector<std::string> none;
    const esf::EvaluationReport empty = esf::evaluate(std::vector<esf::QueryOutcome>{}, 10, none);
    EXPECT_FALSE(esf::confusion_png(empty).empty());
    EXPECT_NE(esf::report_html(empty).find("</html>"), std::string::npos);
    // 60 classes: cells shrink, the image stays bounded.
    std::vector<std::string> classes;
    std::vector<esf::QueryOutcome> outcomes;
    for (int c = 0; c < 60; ++c) {
        classes.push_back("class_with_a_long_name_" + std::to_string(c));
        esf::QueryOutcome o;
        o.true_class = classes.back();
        o.neighbours.push_back({classes[static_cast<std::size_t>(c / 2)], 1.0});
        outcomes.push_back(o);
    }
    const esf::EvaluationReport large = esf::evaluate(outcomes, 10, classes);
    const esf::ReportFiles files = esf::write_report(dir_.string(), large);
    const DecodedPng png = decode(files.confusion_png);
    ASSERT_TRUE(png.ok);
    EXPECT_LT(png.width, 2000u);
}

TEST_F(ReportTest, UnwritableFolderThrowsIoError) {
    fs::create_directories(dir_);
    const fs::path file = dir_ / "file";
    std::ofstream(file) << "x";
    try {
        esf::write_report((file / "sub").string(), sample_report());
        FAIL() << "no exception";
    } catch (const esf::IoError& e) {
        EXPECT_EQ(std::string(e.what()).rfind((file / "sub").string(), 0), 0u) << e.what();
    }
}

}  // namespace
