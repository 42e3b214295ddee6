#include "teejet/layout/layout_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <sstream>

#include "teejet/codec/codec.hpp"
#include "teejet/codec/table.hpp"

namespace teejet::layout {
namespace {

constexpr std::string_view kMechanicsKeys[] = {"closed_deg", "opened_deg"};

double max_position_degrees() {
  return codec::find_field(codec::describe(codec::TargetDegrees{}), "degrees")->max;
}

// closed_deg and opened_deg of `node`, over `base`; nullopt when neither is there.
std::optional<Mechanics> read_mechanics(const yaml::Reader& reader, const YAML::Node& node,
                                        const std::string& section, const Mechanics& base) {
  if (!node["closed_deg"] && !node["opened_deg"]) return std::nullopt;
  Mechanics mechanics = base;
  if (node["closed_deg"]) {
    mechanics.closed_degrees =
        reader.number(node["closed_deg"], section + ".closed_deg", 0, max_position_degrees());
  }
  if (node["opened_deg"]) {
    mechanics.opened_degrees = reader.number(node["opened_deg"], section + ".opened_deg", 0,
                                             codec::kFullTurnOpenedDegrees);
  }
  if (auto valid = codec::check_valve_limits(mechanics.closed_degrees, mechanics.opened_degrees);
      !valid) {
    const char* key = valid.error().field == "closed_degrees" ? "closed_deg" : "opened_deg";
    reader.fail(node[key] ? node[key] : node, section + "." + key, valid.error().complaint);
  }
  return mechanics;
}

// The YAML key of a Layout::make error's field.
std::string key_of(const std::string& field) {
  if (field == "closed_degrees") return "closed_deg";
  if (field == "opened_degrees") return "opened_deg";
  return field;
}

Status system_error(const std::string& what, const std::string& path, int error) {
  return Error{ErrorCode::kSystem, what + " '" + path + "': " + std::strerror(error), error};
}

}  // namespace

Layout read_layout(const yaml::Reader& reader, const YAML::Node& node, const std::string& section) {
  reader.expect_keys(node, section, {"default", "locations"});
  std::optional<Mechanics> default_mechanics;
  if (const auto d = node["default"]) {
    reader.expect_keys(d, section + ".default", kMechanicsKeys);
    default_mechanics = read_mechanics(reader, d, section + ".default", Mechanics{});
  }
  std::vector<Location> locations;
  std::vector<YAML::Node> nodes;
  if (const auto list = node["locations"]) {
    reader.expect_list(list, section + ".locations", "locations");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto entry = list[i];
      const auto where = section + ".locations[" + std::to_string(i) + "]";
      reader.expect_keys(entry, where,
                         {"name", "order", "role", "serial", "closed_deg", "opened_deg"});
      if (!entry["name"]) reader.fail(entry, where + ".name", "is missing");
      Location location;
      location.name = reader.scalar(entry["name"], where + ".name");
      if (auto valid = check_name(location.name); !valid) {
        reader.fail(entry["name"], where + ".name", valid.error().complaint);
      }
      const auto key = section + "." + location.name;
      if (!entry["order"]) reader.fail(entry, key + ".order", "is missing");
      location.order =
          static_cast<unsigned>(reader.integer(entry["order"], key + ".order", 1, kMaxOrder));
      if (entry["role"]) {
        const auto word = reader.scalar(entry["role"], key + ".role");
        const auto role = role_from(word);
        if (!role) {
          std::string allowed;
          for (const auto name : role_names()) {
            allowed += (allowed.empty() ? "" : ", ") + std::string(name);
          }
          reader.fail(entry["role"], key + ".role", "'" + word + "' is not one of " + allowed);
        }
        location.role = *role;
      }
      if (const auto serial_node = entry["serial"]; serial_node && !serial_node.IsNull()) {
        const auto serial = codec::parse_serial(reader.scalar(serial_node, key + ".serial"));
        if (!serial) reader.fail(serial_node, key + ".serial", serial.error().reason);
        location.serial = *serial;
      }
      location.mechanics =
          read_mechanics(reader, entry, key, default_mechanics.value_or(Mechanics{}));
      locations.push_back(std::move(location));
      nodes.push_back(entry);
    }
  }
  std::size_t failed = 0;
  auto layout = Layout::make(locations, default_mechanics, &failed);
  if (!layout) {
    const auto& error = layout.error();
    const auto key = key_of(error.field);
    const auto& entry = nodes.at(failed);
    reader.fail(entry[key] ? entry[key] : entry, section + "." + locations[failed].name + "." + key,
                error.complaint);
  }
  return *std::move(layout);
}

Result<Layout> parse_layout(const std::string& origin, const std::string& text) {
  return yaml::parse<Layout>(origin, text, [](const yaml::Reader& reader, const YAML::Node& root) {
    if (root.IsNull()) return Layout{};
    return read_layout(reader, root, "layout");
  });
}

Result<Layout> load_layout_file(const std::string& path) {
  auto text = yaml::read_file(path);
  if (!text) return text.error();
  return parse_layout(path, *text);
}

std::string to_yaml(const Layout& layout) {
  std::ostringstream out;
  out << "# Where each valve sits on the machine (docs/layout.md). teejet-gateway rewrites this\n"
         "# file on every accepted assignment; comments are not kept.\n";
  const auto mechanics = [&](const Mechanics& m) {
    return "closed_deg: " + yaml::number_text(m.closed_degrees) +
           ", opened_deg: " + yaml::number_text(m.opened_degrees);
  };
  if (layout.default_mechanics()) {
    out << "default: {" << mechanics(*layout.default_mechanics()) << "}\n";
  }
  out << "locations:";
  if (layout.empty()) out << " []";
  out << "\n";
  for (const auto& location : layout.locations()) {
    // Quoted: a name such as "null" or "true" must read back as that word.
    out << "  - {name: \"" << location.name << "\", order: " << location.order
        << ", role: " << to_string(location.role);
    if (location.serial) out << ", serial: " << codec::format_serial(*location.serial);
    if (location.mechanics) out << ", " << mechanics(*location.mechanics);
    out << "}\n";
  }
  return out.str();
}

namespace {

constexpr std::string_view kUnique = "XXXXXX";  // mkstemp's

std::filesystem::path directory_of(const std::filesystem::path& target) {
  return target.has_parent_path() ? target.parent_path() : ".";
}

std::string temporary_prefix(const std::filesystem::path& target) {
  return "." + target.filename().string() + ".";
}

}  // namespace

std::size_t remove_unfinished_saves(const std::string& path) {
  const std::filesystem::path target(path);
  const std::string prefix = temporary_prefix(target);
  std::size_t removed = 0;
  std::error_code error;
  for (const auto& entry : std::filesystem::directory_iterator(directory_of(target), error)) {
    const std::string name = entry.path().filename().string();
    if (name.size() == prefix.size() + kUnique.size() && name.starts_with(prefix) &&
        entry.is_regular_file(error) && std::filesystem::remove(entry.path(), error)) {
      ++removed;
    }
  }
  return removed;
}

Status save_layout_file(const std::string& path, const Layout& layout) {
  const std::filesystem::path target(path);
  const auto directory = directory_of(target);
  std::string temporary = (directory / (temporary_prefix(target) + std::string(kUnique))).string();
  const int fd = ::mkstemp(temporary.data());
  if (fd < 0) return system_error("cannot create a file beside", path, errno);
  const auto fail = [&](const std::string& what, int error) {
    ::close(fd);
    ::unlink(temporary.c_str());
    return system_error(what, temporary, error);
  };
  struct stat existing {};
  const mode_t mode = ::stat(path.c_str(), &existing) == 0 ? existing.st_mode & 07777 : 0644;
  if (::fchmod(fd, mode) != 0) return fail("cannot set the permissions of", errno);
  const std::string text = to_yaml(layout);
  for (std::size_t written = 0; written < text.size();) {
    const auto n = ::write(fd, text.data() + written, text.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return fail("cannot write", errno);
    written += static_cast<std::size_t>(n);
  }
  if (::fsync(fd) != 0) return fail("cannot flush", errno);
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(temporary.c_str());
    return system_error("cannot write", temporary, error);
  }
  if (::rename(temporary.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(temporary.c_str());
    return system_error("cannot replace", path, error);
  }
  // The rename itself reaches the disk only with the directory.
  const int dir = ::open(directory.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) return system_error("cannot open the directory of", path, errno);
  const int synced = ::fsync(dir);
  const int error = errno;
  ::close(dir);
  if (synced != 0) return system_error("cannot flush the directory of", path, error);
  return {};
}

}  // namespace teejet::layout
