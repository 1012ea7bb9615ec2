ModelSurface sample_model_surface(const Mesh& mesh, double scale, std::size_t count,
                                  std::uint64_t seed) {
    check_mesh(mesh, "model surface");
    if (count == 0) throw std::invalid_argument("model surface: no samples asked for");
    if (!(scale > 0.0) || !std::isfinite(scale))
        throw std::invalid_argument("model surface: scale must be positive and finite");
    std::vector<double> cumulative(mesh.triangles.size());
    double total = 0.0;
    for (std::size_t t = 0; t < mesh.triangles.size(); ++t) {
        const Eigen::Vector3i& f = mesh.triangles[t];
        const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(f[0])].cast<double>();
        const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(f[1])].cast<double>();
        const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(f[2])].cast<double>();
        total += 0.5 * (b - a).cross(c - a).norm();
        cumulative[t] = total;
    }
    if (!(total > 0.0)) throw std::invalid_argument("model surface: the mesh has no area");

    ModelSurface surface;
    surface.scale = scale;
    surface.diameter = 2.0 * mesh.bounding_radius() * scale;
    const Eigen::Vector3d centre = (0.5 * (mesh.min_corner() + mesh.max_corner())).cast<double>();
    detail::SplitMix64 random(seed);
    std::size_t inward = 0;
    for (std::size_t i = 0; i < count; ++i) {
        // Stratified along the cumulative area: evenly spread, still random.
        const double target =
            (static_cast<double>(i) + random.uniform()) / static_cast<double>(count) * total;
        const std::size_t t = static_cast<std::size_t>(
            std::lower_bound(cumulative.begin(), cumulative.end(), target) - cumulative.begin());
        const Eigen::Vector3i& f = mesh.triangles[std::min(t, mesh.triangles.size() - 1)];
        const Eigen::Vector3d a = mesh.vertices[static_cast<std::size_t>(f[0])].cast<double>();
        const Eigen::Vector3d b = mesh.vertices[static_cast<std::size_t>(f[1])].cast<double>();
        const Eigen::Vector3d c = mesh.vertices[static_cast<std::size_t>(f[2])].cast<double>();
        double r1 = random.uniform(), r2 = random.uniform();
        if (r1 + r2 > 1.0) {
            r1 = 1.0 - r1;
            r2 = 1.0 - r2;
        }
        const Eigen::Vector3d p = a + r1 * (b - a) + r2 * (c - a);
        Eigen::Vector3d n = (b - a).cross(c - a);
        n = n.norm() > 0.0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::UnitZ();
        inward += n.dot(p - centre) < 0.0;
        surface.points.push_back((p * scale).cast<float>());
        surface.normals.push_back(n.cast<float>());
    }
    if (2 * inward > count)
        for (Eigen::Vector3f& n : surface.normals) n = -n;
    return surface;
}
