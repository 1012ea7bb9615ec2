// The recording source of esf live (live_source.hpp); the Kinect source is kinect_source.cpp.

#include "live_source.hpp"

#include <optional>

namespace esf::cli {

namespace {

class RecordingSource final : public FrameSource {
  public:
    explicit RecordingSource(const std::string& folder) : reader_(folder) {}

    FrameWait next(KinectFrame& frame, std::chrono::milliseconds) override {
        std::optional<KinectFrame> f = reader_.next();
        if (!f) return FrameWait::kEnded;
        frame = std::move(*f);
        return FrameWait::kFrame;
    }
    std::size_t skipped() const override { return 0; }
    std::string message() const override { return {}; }
    std::string name() const override { return "recording " + reader_.folder(); }
    bool stop() override { return true; }

  private:
    KinectRecordingReader reader_;
};

}  // namespace

std::unique_ptr<FrameSource> open_recording_source(const std::string& folder) {
    return std::make_unique<RecordingSource>(folder);
}

}  // namespace esf::cli
