// urdfdom's parser, made to return its complaints instead of printing them: the model,
// or null and urdfdom's error messages (which name the element: "Malformed parent
// origin element for joint [j2]"). Nothing thrown escapes.
//
// urdfdom reports through console_bridge's global output handler. While it parses,
// parse_model() puts its own handler in place and restores the previous one after;
// parses are serialised by a mutex, and console_bridge messages that other threads log
// meanwhile are collected too (they would appear in a failed parse's message).
//
// urdfdom 3.0 hands the text of some malformed values to console_bridge as the printf
// format itself (a radius, length, box size, mass, <origin> xyz/rpy, the robot's version,
// a material's name or colour): a '%' in such a value makes printf read arguments that
// were never passed, and the process crashes (a '%n' would write). The document is
// therefore read first with the same XML parser (tinyxml, a dependency of urdfdom), and a
// '%' in any attribute value or text is refused, naming the attribute or element and its
// line, before urdfdom sees it. A mesh's `filename` is exempt: urdfdom never formats it,
// and URL-escaped paths carry '%'.
//
// tinyxml also trusts a UTF-8 lead byte: it steps over as many bytes as the lead byte
// announces without looking for the end of the text, so a lead byte near the end (or
// before a NUL) makes it read past the buffer (a fuzzed document: a heap overflow under
// AddressSanitizer), and a lone 0xEF there made its line count loop forever (CVE-2021-42260,
// patched in Debian's 2.6.2-6, not in every tinyxml a user links). Before
// either parser sees it, the document must therefore be well-formed UTF-8 (RFC 3629: no
// overlong forms, no surrogates, nothing above U+10FFFF) without NUL bytes, as XML
// requires of a document with no declared encoding; otherwise it is refused, naming the
// byte's offset and line.
#pragma once

#include <console_bridge/console.h>
#include <tinyxml.h>
#include <urdf_parser/urdf_parser.h>

#include <cstdio>
#include <cstring>
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

/// The node after `node` in document order (depth first), or null; no recursion, so
/// the depth of the document does not bound the stack.
inline const TiXmlNode* next_node(const TiXmlNode* node) noexcept {
  if (node->FirstChild() != nullptr) return node->FirstChild();
  for (; node != nullptr; node = node->Parent()) {
    if (node->NextSibling() != nullptr) return node->NextSibling();
  }
  return nullptr;
}

/// Empty if `xml` is well-formed UTF-8 without NUL bytes; otherwise names the first
/// offending byte (its offset from 0, its line from 1, its value).
inline std::string find_invalid_utf8(const std::string& xml) {
  const auto byte = [&xml](std::size_t i) { return static_cast<unsigned char>(xml[i]); };
  std::size_t line = 1;
  for (std::size_t i = 0; i < xml.size();) {
    const unsigned char lead = byte(i);
    // The continuation bytes a lead byte announces, and the range of the first of them
    // (narrower than 0x80-0xBF where an overlong form, a surrogate or a code point above
    // U+10FFFF would start).
    int more = 0;
    unsigned char first_lo = 0x80, first_hi = 0xBF;
    if (lead >= 0x01 && lead <= 0x7F) {
      more = 0;
    } else if (lead >= 0xC2 && lead <= 0xDF) {
      more = 1;
    } else if (lead >= 0xE0 && lead <= 0xEF) {
      more = 2;
      if (lead == 0xE0) first_lo = 0xA0;
      if (lead == 0xED) first_hi = 0x9F;
    } else if (lead >= 0xF0 && lead <= 0xF4) {
      more = 3;
      if (lead == 0xF0) first_lo = 0x90;
      if (lead == 0xF4) first_hi = 0x8F;
    } else {
      more = -1;  // NUL, a continuation byte, 0xC0, 0xC1, 0xF5-0xFF
    }
    bool ok = more >= 0 && i + static_cast<std::size_t>(more) < xml.size();
    for (int k = 1; ok && k <= more; ++k) {
      const unsigned char c = byte(i + static_cast<std::size_t>(k));
      ok = k == 1 ? (c >= first_lo && c <= first_hi) : (c >= 0x80 && c <= 0xBF);
    }
    if (!ok) {
      char hex[8];
      std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(lead));
      return "byte " + std::to_string(i) + " (line " + std::to_string(line) + ", " + hex +
             (lead == 0 ? ", a NUL byte" : "") +
             ") is not well-formed UTF-8 (the reader takes UTF-8 documents only)";
    }
    if (lead == '\n') ++line;
    i += static_cast<std::size_t>(more) + 1;
  }
  return {};
}

/// Empty if no attribute value (other than `filename`) and no text of the document holds
/// a '%'; otherwise names the first one. A document tinyxml cannot read passes here:
/// urdfdom then refuses it with tinyxml's own (constant) message.
inline std::string find_format_character(const std::string& xml) {
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error()) return {};
  const auto line = [](const TiXmlBase& item) { return std::to_string(item.Row()); };
  for (const TiXmlNode* node = doc.FirstChild(); node != nullptr; node = next_node(node)) {
    if (const TiXmlElement* element = node->ToElement()) {
      for (const TiXmlAttribute* a = element->FirstAttribute(); a != nullptr; a = a->Next()) {
        if (std::strcmp(a->Name(), "filename") == 0 || std::strchr(a->Value(), '%') == nullptr)
          continue;
        return "attribute '" + std::string(a->Name()) + "' of <" + element->Value() + "> at line " +
               line(*a);
      }
    } else if (const TiXmlText* text = node->ToText()) {
      if (std::strchr(text->Value(), '%') == nullptr) continue;
      const TiXmlNode* parent = text->Parent();
      return "the text of <" + std::string(parent != nullptr ? parent->Value() : "") +
             "> at line " + line(*text);
    }
  }
  return {};
}

/// Parses a URDF document. Returns the model, or null with `error` set.
inline ::urdf::ModelInterfaceSharedPtr parse_model(const std::string& xml, std::string& error) {
  const std::string encoding = find_invalid_utf8(xml);
  if (!encoding.empty()) {
    error = "the document's " + encoding;
    return nullptr;
  }
  const std::string percent = find_format_character(xml);
  if (!percent.empty()) {
    error = percent + " contains '%' (refused: urdfdom 3.0 would pass it to printf as a format)";
    return nullptr;
  }
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

/// Reads a whole file into `text`. Returns false, with `error` set, if it cannot.
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
