// urdfdom's parser, made to return its complaints instead of printing them: the model,
// or null and urdfdom's error messages (which name the element: "Malformed parent
// origin element for joint [j2]"). Nothing thrown escapes.
//
// urdfdom reports through console_bridge's global output handler. While it parses,
// parse_model() puts its own handler in place and restores the previous one after;
// parses are serialised by a mutex, and console_bridge messages that other threads log
// meanwhile are collected too (they would appear in a failed parse's message).
#pragma once

#include <console_bridge/console.h>
#include <urdf_parser/urdf_parser.h>

#include <fstream>
#include <mutex>
#include <sstream>
#include <string>

namespace inhand::urdf::detail {

/// Collects console_bridge messages at error level, "; "-separated.
class MessageCollector : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level < console_bridge::CONSOLE_BRIDGE_LOG_ERROR) return;
    add(text);
  }
  void add(const std::string& text) {
    if (!messages_.empty()) messages_ += "; ";
    messages_ += text;
  }
  const std::string& messages() const noexcept { return messages_; }

 private:
  std::string messages_;
};

inline std::mutex& parse_mutex() {
  static std::mutex m;
  return m;
}

/// Parses a URDF document. Returns the model, or null with `error` set.
inline ::urdf::ModelInterfaceSharedPtr parse_model(const std::string& xml, std::string& error) {
  std::lock_guard<std::mutex> lock(parse_mutex());
  MessageCollector collector;
  console_bridge::OutputHandler* previous = console_bridge::getOutputHandler();
  console_bridge::useOutputHandler(&collector);
  ::urdf::ModelInterfaceSharedPtr model;
  try {
    model = ::urdf::parseURDF(xml);
  } catch (const std::exception& e) {
    model.reset();
    collector.add(e.what());
  } catch (...) {
    model.reset();
    collector.add("unknown exception");
  }
  console_bridge::useOutputHandler(previous);
  if (!model) {
    error = "urdfdom rejected the document (XML or URDF): " +
            (collector.messages().empty() ? std::string("no message") : collector.messages());
  }
  return model;
}

/// Reads a whole file into `text`. Returns false, with `error` set, if it cannot.
/// Clears the links' child and parent-joint pointers so that the model is freed even
/// when its link graph has a cycle (urdfdom keeps children by shared pointer, and does
/// not refuse every cyclic document: such a model would otherwise never be freed).
inline void release_model(::urdf::ModelInterface& model) noexcept {
  for (auto& entry : model.links_) {
    if (!entry.second) continue;
    entry.second->child_links.clear();
    entry.second->child_joints.clear();
    entry.second->parent_joint.reset();
  }
  model.root_link_.reset();
}

inline bool read_text_file(const std::string& path, std::string& text, std::string& error) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream buffer;
  if (in) buffer << in.rdbuf();
  if (!in || in.bad()) {
    error = "cannot read file '" + path + "'";
    return false;
  }
  text = buffer.str();
  return true;
}

}  // namespace inhand::urdf::detail
