// pcl_esf_describe FILE: PCL's own pipeline for one cloud, as a whole process:
// pcl::io::loadPCDFile, non-finite points dropped, pcl::ESFEstimation, one CSV line
// "FILE,v0,...,v639" on stdout. The counterpart of `esf describe --threads 1 FILE` in
// bench/cloud_io_batch.sh.

#include <pcl/features/esf.h>
#include <pcl/io/pcd_io.h>
#include <pcl/point_types.h>

#include <cmath>
#include <cstdio>
#include <string>

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: pcl_esf_describe FILE.pcd\n");
        return 1;
    }
    const std::string file = argv[1];
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
