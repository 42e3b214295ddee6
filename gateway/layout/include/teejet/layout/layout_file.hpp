#pragma once

// A layout as YAML, in the gateway's configuration (`layout:`) or in a file of its own, which
// the gateway owns and rewrites on every accepted assignment:
//
//   default: {closed_deg: 0, opened_deg: 90}   # mechanics of every place without its own
//   locations:
//     - {name: left-master, order: 1, role: master, serial: TJV000101, opened_deg: 360}
//     - {name: section-01, order: 2, role: section, serial: TJV000102}
//     - {name: section-02, order: 3}              # no valve yet; role section by default

#include <yaml-cpp/yaml.h>

#include <string>

#include "teejet/core/result.hpp"
#include "teejet/layout/layout.hpp"
#include "teejet/yaml/reader.hpp"

namespace teejet::layout {

// Reads the mapping above; every mistake fails through `reader` with line and key
// ("<section>.<location>.<key>").
Layout read_layout(const yaml::Reader& reader, const YAML::Node& node, const std::string& section);

Result<Layout> parse_layout(const std::string& origin, const std::string& text);
Result<Layout> load_layout_file(const std::string& path);

// The text that parse_layout reads back as `layout`, in machine order.
std::string to_yaml(const Layout& layout);

// Replaces the file at `path` with `layout` so that a power cut or a kill at any moment leaves
// either the old file or the new one, whole: written beside it, flushed to the disk, renamed
// over it, and the directory flushed. The file keeps its permissions (0644 when new).
Status save_layout_file(const std::string& path, const Layout& layout);

// The files that saves of `path` interrupted by a power cut or a kill left beside it (hidden,
// ".<name>.XXXXXX"), removed; returns how many. For the file's owner at start, before it saves.
std::size_t remove_unfinished_saves(const std::string& path);

// The gateway's own layout file: every accepted change rewrites it whole (save_layout_file).
class LayoutFileStore final : public LayoutStore {
 public:
  explicit LayoutFileStore(std::string path) : path_(std::move(path)) {}
  Status save(const Layout& layout) override { return save_layout_file(path_, layout); }

 private:
  const std::string path_;
};

}  // namespace teejet::layout
