// The run settings of an experiment config: its [render], [measure] and [trace] sections read into
// RunRender (experiments/config.hpp), each key typed and bounded, and the checks between them;
// experiments/config.cpp reads the rest ([experiment], [findings], the axes and sweeps) and calls these.
// Errors are InputError "FILE:LINE: KEY: what is wrong" (ConfigReader).
#pragma once
#include <optional>

#include <toml++/toml.h>

#include "experiments/config.hpp"
#include "experiments/config_reader.hpp"

namespace bvhlab::config_detail {

// Where settings that are checked against each other were written (for the errors of checkRunSettings).
struct SettingNodes {
  const toml::node* cameraPath = nullptr;     // [render] camera_path
  const toml::node* frames = nullptr;         // [render] frames
  const toml::node* measureMinNode = nullptr; // [measure] min_frames
  std::optional<int> measureMin;              // its value
  const toml::node* maxFrames = nullptr;      // [measure] max_frames
  const toml::node* programCopies = nullptr;  // [measure] program_copies
};

void readRenderSection(ConfigReader& r, const toml::node& section, RunRender& out, SettingNodes& nodes);
void readMeasureSection(ConfigReader& r, const toml::node& section, RunRender& out, SettingNodes& nodes);
void readTraceSection(ConfigReader& r, const toml::node& section, RunRender& out);
// After every section is read: [measure] min_frames against [render] frames (one value, given in one
// place), max_frames >= min_frames, program_copies needing interleave.
void checkRunSettings(ConfigReader& r, RunRender& render, const SettingNodes& nodes);

}  // namespace bvhlab::config_detail
