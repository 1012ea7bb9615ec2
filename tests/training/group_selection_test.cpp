// Group selection (plan_models): folds split each category's groups, the two sides of a fold
// never share a group, and selections by name are checked against the root.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

#include "esf/mesh/mesh.hpp"
#include "esf/training/training.hpp"

namespace fs = std::filesystem;

namespace {

class GroupSelectionTest : public ::testing::Test {
  protected:
    void SetUp() override {
        root_ = fs::temp_directory_path() /
                ("esf_groups_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
                 "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
        fs::remove_all(root_);
        esf::Mesh mesh;
        mesh.vertices = {{0, 0, 0}, {0.1f, 0, 0}, {0, 0.1f, 0}, {0, 0, 0.1f}};
        mesh.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
        std::ofstream catalog;
        std::string rows = "file,category,source,model,group,extent,metric\n";
        // box: 9 models in 7 groups (b0 and b1 hold two each); can: 4 groups; apple: 1.
        const auto add = [&](const std::string& category, const std::string& name,
                             const std::string& group, bool metric) {
            fs::create_directories(root_ / category);
            esf::write_ply_mesh((root_ / category / (name + ".ply")).string(), mesh);
            rows += category + "/" + name + ".ply," + category + ",test," + name + "," + group +
                    ",0.1," + (metric ? "yes" : "no") + "\n";
        };
        // Names built by append: GCC 12 warns falsely (-Wrestrict) on "b" + std::to_string(i).
        const auto named = [](const char* prefix, int i) {
            std::string name(prefix);
            name.append(std::to_string(i));
            return name;
        };
        for (int i = 0; i < 9; ++i)
            add("box", named("box", i), named("b", i < 4 ? i / 2 : i), true);
        for (int i = 0; i < 4; ++i) add("can", named("can", i), named("c", i), i != 2);
        add("apple", "apple0", "a0", true);
        std::ofstream(root_ / "catalog.csv") << rows;
    }
    void TearDown() override { fs::remove_all(root_); }

    std::set<std::string> groups_of(const esf::GroupSelection& selection) const {
        std::set<std::string> groups;
        for (const auto& p : esf::plan_models(root_.string(), "", true, selection))
            groups.insert(p.group);
        return groups;
    }

    fs::path root_;
};

TEST_F(GroupSelectionTest, FoldsPartitionTheGroupsOfEachCategory) {
    const std::set<std::string> all = groups_of({});
    ASSERT_EQ(all.size(), 7u + 4u + 1u);
    for (const int folds : {2, 3}) {
        std::map<std::string, int> seen;
        for (int k = 0; k < folds; ++k) {
            esf::GroupSelection fold;
            fold.fold = k;
            fold.folds = folds;
            const std::set<std::string> in = groups_of(fold);
            fold.other_folds = true;
            const std::set<std::string> out = groups_of(fold);
            for (const std::string& g : in) {
                ++seen[g];
                EXPECT_FALSE(out.count(g)) << g << " on both sides of fold " << k;
            }
            EXPECT_EQ(in.size() + out.size(), all.size());
            EXPECT_TRUE(out.count("a0")) << "a category of one group stays on the training side";
            // Round-robin: every fold holds a share of the boxes and of the cans.
            std::size_t boxes = 0, cans = 0;
            for (const std::string& g : in) (g[0] == 'b' ? boxes : cans) += g[0] != 'a';
            EXPECT_GE(boxes, 7u / folds);
            EXPECT_GE(cans, 4u / folds);
        }
        EXPECT_EQ(seen.size(), all.size() - 1) << "every group of a multi-group category";
        for (const auto& [group, count] : seen) EXPECT_EQ(count, 1) << group;
    }
}

TEST_F(GroupSelectionTest, GroupsKeepTheirModelsTogetherAndScale) {
    esf::GroupSelection only;
    only.only = {"b0", "c2"};
    const auto plans = esf::plan_models(root_.string(), "", true, only);
    ASSERT_EQ(plans.size(), 3u);  // box0, box1 (group b0), can2
    for (const auto& p : plans) {
        EXPECT_EQ(p.rescale, p.file.name == "can2") << p.file.name;
        if (p.rescale) {
            EXPECT_GT(p.target_extent, 0.0);
        }
    }
    esf::GroupSelection except;
    except.except = {"b0"};
    EXPECT_EQ(esf::plan_models(root_.string(), "", true, except).size(), 14u - 2u);
}

TEST_F(GroupSelectionTest, CategoriesNarrowTheModelsAndLeaveTheFoldsAsTheyAre) {
    esf::GroupSelection cans;
    cans.categories = {"can"};
    EXPECT_EQ(groups_of(cans), (std::set<std::string>{"c0", "c1", "c2", "c3"}));
    cans.categories = {"can", "apple"};
    EXPECT_EQ(groups_of(cans).size(), 5u);
    // Each fold's cans are the cans of that fold without the category filter.
    for (int k = 0; k < 3; ++k)
        for (const bool other : {false, true}) {
            esf::GroupSelection fold;
            fold.fold = k;
            fold.folds = 3;
            fold.other_folds = other;
            std::set<std::string> expected;
            for (const std::string& g : groups_of(fold))
                if (g[0] == 'c') expected.insert(g);
            fold.categories = {"can"};
            if (expected.empty()) {
                EXPECT_THROW(groups_of(fold), std::invalid_argument);
            } else {
                EXPECT_EQ(groups_of(fold), expected) << "fold " << k << " other " << other;
            }
        }
}

TEST_F(GroupSelectionTest, RejectsUnknownGroupsAndBadFolds) {
    esf::GroupSelection unknown;
    unknown.only = {"nope"};
    EXPECT_THROW(esf::plan_models(root_.string(), "", true, unknown), std::invalid_argument);
    esf::GroupSelection no_such_category;
    no_such_category.categories = {"can", "pear"};
    try {
        esf::plan_models(root_.string(), "", true, no_such_category);
        FAIL() << "an unknown category was taken";
    } catch (const std::invalid_argument& e) {
        EXPECT_NE(std::string(e.what()).find("no category 'pear'"), std::string::npos) << e.what();
    }
    esf::GroupSelection s;
    EXPECT_NO_THROW(esf::parse_fold("1/3", s));
    EXPECT_EQ(s.fold, 1);
    EXPECT_EQ(s.folds, 3);
    for (const char* bad : {"3/3", "-1/3", "1/1", "1", "a/b", "1/3x", ""})
        EXPECT_THROW(esf::parse_fold(bad, s), std::invalid_argument) << bad;
}

}  // namespace
