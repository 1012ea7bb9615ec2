// pcl_esf_describe FILE...: PCL's own pipeline for each cloud, in one process:
// pcl::io::loadPCDFile, non-finite points dropped, pcl::ESFEstimation, one CSV line
// "FILE,v0,...,v639" per file on stdout. The counterpart of `esf describe --threads 1 FILE...`
// in bench/cloud_io_batch.sh (one file per process, or all files in one, as `xargs` runs them).

#include <pcl/features/esf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

int describe(const std::string& file) {
    pcl::PointCloud<pcl::PointXYZ> raw;
    if (pcl::io::loadPCDFile(file, raw) != 0) {
        std::fprintf(stderr, "pcl_esf_describe: cannot read %s\n", file.c_str());
        return 2;
    }
    pcl::PointCloud<pcl::PointXYZ>::Ptr cloud(new pcl::PointCloud<pcl::PointXYZ>);
    cloud->reserve(raw.size());
    for (const auto& p : raw) {
        if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) cloud->push_back(p);
    }
    if (cloud->empty()) {
        std::fprintf(stderr, "pcl_esf_describe: %s has no finite points\n", file.c_str());
        return 2;
    }
    pcl::ESFEstimation<pcl::PointXYZ, pcl::ESFSignature640> esf;
    esf.setInputCloud(cloud);
    pcl::PointCloud<pcl::ESFSignature640> out;
    esf.compute(out);
    std::string line = file;
    char value[32];
    for (const float v : out[0].histogram) {
        std::snprintf(value, sizeof(value), ",%.9g", static_cast<double>(v));
        line += value;
    }
    std::printf("%s\n", line.c_str());
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: pcl_esf_describe FILE.pcd...\n");
        return 1;
    }
    int status = 0;
    for (int i = 1; i < argc; ++i)
        if (const int rc = describe(argv[i]); rc != 0) status = rc;
    return status;
}
