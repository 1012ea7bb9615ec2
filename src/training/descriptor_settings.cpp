#include "esf/training/descriptor_settings.hpp"

#include <algorithm>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

namespace esf {

namespace {

const SettingValue* find_setting(const Settings& settings, const std::string& key) {
    const auto it = settings.find(key);
    return it == settings.end() ? nullptr : &it->second;
}

std::int64_t integer_setting(const Settings& settings, const std::string& key,
                             std::int64_t fallback) {
    const SettingValue* value = find_setting(settings, key);
    if (!value) return fallback;
    if (const auto* i = std::get_if<std::int64_t>(value)) return *i;
    throw std::invalid_argument("setting " + key + " = " + to_string(*value) +
                                " is not an integer");
}

int int_setting(const Settings& settings, const std::string& key, int fallback) {
    const std::int64_t v = integer_setting(settings, key, fallback);
    if (v < std::numeric_limits<int>::min() || v > std::numeric_limits<int>::max())
        throw std::invalid_argument("setting " + key + " = " + std::to_string(v) +
                                    " is out of range");
    return static_cast<int>(v);
}

double real_setting(const Settings& settings, const std::string& key, double fallback) {
    const SettingValue* value = find_setting(settings, key);
    if (!value) return fallback;
    if (const auto* d = std::get_if<double>(value)) return *d;
    if (const auto* i = std::get_if<std::int64_t>(value)) return static_cast<double>(*i);
    throw std::invalid_argument("setting " + key + " = " + to_string(*value) + " is not a number");
}

std::string text_setting(const Settings& settings, const std::string& key,
                         const std::string& fallback) {
    const SettingValue* value = find_setting(settings, key);
    if (!value) return fallback;
    if (const auto* s = std::get_if<std::string>(value)) return *s;
    throw std::invalid_argument("setting " + key + " = " + to_string(*value) + " is not text");
}

}  // namespace

std::uint64_t stored_seed(const Settings& settings) {
    const SettingValue* value = find_setting(settings, "seed");
    if (!value) return 0;
    if (const auto* i = std::get_if<std::int64_t>(value)) {
        if (*i < 0) throw std::invalid_argument("setting seed = " + std::to_string(*i) + " < 0");
        return static_cast<std::uint64_t>(*i);
    }
    if (const auto* s = std::get_if<std::string>(value)) {
        std::size_t used = 0;
        std::uint64_t seed = 0;
        try {
            seed = std::stoull(*s, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used == s->size() && !s->empty() && s->front() != '-') return seed;
    }
    throw std::invalid_argument("setting seed = " + to_string(*value) + " is not a seed");
}

Settings descriptor_settings(const DescriptorSetup& setup) {
    const DescriptorInfo info = descriptor_info(setup.name);  // throws for an unknown name
    Settings settings = {
        {"descriptor", setup.name},
        {"descriptor_version", std::int64_t{info.version}},
        {"descriptor_dimension", std::int64_t{info.dimension}},
    };
    if (info.esf_options) {
        const EsfOptions& e = setup.esf;
        settings.emplace("esf_samples", std::int64_t{e.samples});
        settings.emplace("esf_grid_size", std::int64_t{e.grid_size});
        settings.emplace("esf_sampler", std::string(to_string(e.sampler)));
        settings.emplace("esf_max_attempts_per_sample", std::int64_t{e.max_attempts_per_sample});
        return settings;
    }
    const DescriptorOptions& d = setup.options;
    settings.emplace("descriptor_samples", std::int64_t{d.samples});
    settings.emplace("descriptor_leaf_factor", static_cast<double>(d.leaf_factor));
    settings.emplace("descriptor_normal_radius_factor",
                     static_cast<double>(d.normal_radius_factor));
    settings.emplace("descriptor_remove_outliers", std::int64_t{d.remove_outliers ? 1 : 0});
    if (info.angles_weight) {
        settings.emplace("descriptor_angles_weight", d.angles_weight);
        settings.emplace("descriptor_primitive_weight", d.primitive_weight);
    }
    return settings;
}

DescriptorSetup read_descriptor_setup(const Settings& settings, const DescriptorKind& kind) {
    const int version = stored_descriptor_version(kind.name);  // throws for an unknown name
    DescriptorSetup setup;
    setup.name = kind.name;
    if (kind.version != version)
        throw std::invalid_argument("descriptor " + kind.name + " version " +
                                    std::to_string(kind.version) +
                                    ", but this build computes version " + std::to_string(version) +
                                    ": retrain the database");
    const int dimension = descriptor_info(kind.name).dimension;
    if (kind.dimension != dimension)
        throw std::invalid_argument(
            "descriptor " + kind.name + " has " + std::to_string(kind.dimension) +
            " floats, but this build computes " + std::to_string(dimension));
    // The settings describe the kind the database was trained with; a database may also hold
    // kinds added later, whose version and dimension are checked above.
    if (text_setting(settings, "descriptor", kind.name) == kind.name) {
        const std::int64_t stored_version =
            integer_setting(settings, "descriptor_version", version);
        if (stored_version != version)
            throw std::invalid_argument(
                "setting descriptor_version = " + std::to_string(stored_version) +
                ", but this build computes " + kind.name + " version " + std::to_string(version) +
                ": retrain the database");
        const std::int64_t stored_dimension =
            integer_setting(settings, "descriptor_dimension", dimension);
        if (stored_dimension != dimension)
            throw std::invalid_argument(
                "setting descriptor_dimension = " + std::to_string(stored_dimension) + ", but " +
                kind.name + " has " + std::to_string(dimension) + " floats");
    }
    const std::uint64_t seed = stored_seed(settings);
    const DescriptorInfo info = descriptor_info(kind.name);
    if (info.esf_options) {
        EsfOptions& e = setup.esf;
        e.samples = int_setting(settings, "esf_samples", e.samples);
        e.grid_size = int_setting(settings, "esf_grid_size", e.grid_size);
        e.sampler =
            parse_enum<EsfSampler>(text_setting(settings, "esf_sampler", to_string(e.sampler)));
        e.max_attempts_per_sample =
            int_setting(settings, "esf_max_attempts_per_sample", e.max_attempts_per_sample);
        e.seed = seed;
        try {
            EsfEstimator check(e);
        } catch (const std::invalid_argument& error) {
            throw std::invalid_argument(std::string("esf settings: ") + error.what());
        }
    } else {
        DescriptorOptions& o = setup.options;
        o.seed = seed;
        o.samples = int_setting(settings, "descriptor_samples", o.samples);
        o.leaf_factor = static_cast<float>(
            real_setting(settings, "descriptor_leaf_factor", static_cast<double>(o.leaf_factor)));
        o.normal_radius_factor =
            static_cast<float>(real_setting(settings, "descriptor_normal_radius_factor",
                                            static_cast<double>(o.normal_radius_factor)));
        const std::int64_t remove =
            integer_setting(settings, "descriptor_remove_outliers", o.remove_outliers ? 1 : 0);
        if (remove != 0 && remove != 1)
            throw std::invalid_argument("setting descriptor_remove_outliers = " +
                                        std::to_string(remove) + " is not 0 or 1");
        o.remove_outliers = remove == 1;
        if (info.angles_weight) {
            o.angles_weight = real_setting(settings, "descriptor_angles_weight", o.angles_weight);
            o.primitive_weight =
                real_setting(settings, "descriptor_primitive_weight", o.primitive_weight);
        }
        check_descriptor_options(kind.name, o);  // throws for options out of range
    }
    return setup;
}

void check_descriptor_setup(const DescriptorSetup& setup) {
    if (descriptor_info(setup.name).esf_options)  // throws for an unknown name
        EsfEstimator check(setup.esf);            // throws for options out of range
    else
        check_descriptor_options(setup.name, setup.options);
}

DescriptorKind descriptor_kind(const DescriptorSetup& setup) {
    const DescriptorInfo info = descriptor_info(setup.name);
    return {setup.name, info.version, info.dimension};
}

std::unique_ptr<GlobalDescriptor> make_descriptor(const DescriptorSetup& setup,
                                                  std::uint64_t seed) {
    if (descriptor_info(setup.name).esf_options) {  // throws for an unknown name
        EsfOptions esf = setup.esf;
        esf.seed = seed;
        return make_esf_descriptor(esf);
    }
    DescriptorOptions options = setup.options;
    options.seed = seed;
    return make_descriptor(setup.name, options);
}

}  // namespace esf
