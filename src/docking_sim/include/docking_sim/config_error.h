// Errors in configuration files, naming the file and the field (ROS-free).
#pragma once

#include <stdexcept>
#include <string>

namespace docking_sim {

/// Thrown by every loader when a file is missing, unreadable or has a bad field. what() reads
/// "<file>: <field>: <problem>", so the message alone tells a user what to fix.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(const std::string& file, const std::string& field, const std::string& problem)
      : std::runtime_error(file + ": " + (field.empty() ? std::string("") : field + ": ") + problem),
        file_(file),
        field_(field) {}
  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }

 private:
  std::string file_;
  std::string field_;
};

}  // namespace docking_sim
