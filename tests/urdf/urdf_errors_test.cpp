// Malformed and unsupported URDF documents: each is refused with an error that names
// the offending element (link or joint), and none crashes or throws.
// Every case reads one finger {"f", <root, mostly "palm">, <tip>} from a small document
// built around the case's joint; the refusals are printed ("[ refused  ]").
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdlib>
#include <random>
#include <string>
#include <vector>

#include "inhand/urdf.hpp"

namespace {

using inhand::urdf::FingerSpec;

// A revolute joint `name` from `parent` to `child` with the given inner XML.
std::string joint(const std::string& name, const std::string& type, const std::string& parent,
                  const std::string& child, const std::string& inner) {
  return "<joint name='" + name + "' type='" + type + "'><parent link='" + parent +
         "'/><child link='" + child + "'/>" + inner + "</joint>";
}
const std::string kLimit = "<limit lower='-1' upper='1' effort='1' velocity='1'/>";
const std::string kAxis = "<axis xyz='1 0 0'/>";

// palm -> l1 (j1, revolute) -> l2 (`type` joint `name` with `inner`) -> tip (fixed).
std::string hand(const std::string& name, const std::string& type, const std::string& inner,
                 const std::string& extra = "") {
  return "<robot name='r'><link name='palm'/><link name='l1'/><link name='l2'/>"
         "<link name='tip'/>" +
         joint("j1", "revolute", "palm", "l1", kAxis + kLimit) +
         joint(name, type, "l1", "l2", inner) + joint("jtip", "fixed", "l2", "tip", "") + extra +
         "</robot>";
}

struct BadCase {
  const char* what;
  std::string xml;
  std::string tip;
  const char* must_name;  // appears in the error text
  std::string root = "palm";
};

std::vector<BadCase> bad_cases() {
  const std::string ok_inner = kAxis + kLimit;
  return {
      {"prismatic joint", hand("slider", "prismatic", ok_inner), "tip", "slider"},
      {"floating joint", hand("loose", "floating", ""), "tip", "loose"},
      {"planar joint", hand("flat", "planar", "<axis xyz='0 0 1'/>"), "tip", "flat"},
      {"missing tip link", hand("j2", "revolute", ok_inner), "no_such_tip", "no_such_tip"},
      {"tip not below root",
       hand("j2", "revolute", ok_inner,
            "<link name='other'/>" + joint("jo", "fixed", "palm", "other", "")),
       "other", "other", "l2"},
      {"missing root link", hand("j2", "revolute", ok_inner), "tip", "nohand", "nohand"},
      {"mimic of a joint outside the finger",
       hand("j2", "revolute", ok_inner + "<mimic joint='elsewhere'/>",
            "<link name='x'/>" + joint("elsewhere", "revolute", "palm", "x", ok_inner)),
       "tip", "elsewhere"},
      {"mimic of a joint that is not in the document",
       hand("j2", "revolute", ok_inner + "<mimic joint='ghost'/>"), "tip", "ghost"},
      {"zero axis", hand("still", "revolute", "<axis xyz='0 0 0'/>" + kLimit), "tip", "still"},
      {"non-finite origin", hand("j2", "revolute", "<origin xyz='nan 0 0'/>" + ok_inner), "tip",
       "j2"},
      {"infinite rotation", hand("j2", "revolute", "<origin rpy='0 inf 0'/>" + ok_inner), "tip",
       "j2"},
      {"lower > upper",
       hand("backwards", "revolute",
            kAxis + "<limit lower='1' upper='-1' effort='1' velocity='1'/>"),
       "tip", "backwards"},
      {"revolute joint without limits", hand("nolimit", "revolute", kAxis), "tip", "nolimit"},
      {"malformed XML", "<robot name='r'><link name='palm'/><link name='tip'", "tip", "XML"},
      {"no movable joint",
       "<robot name='r'><link name='palm'/><link name='tip'/>" +
           joint("weld", "fixed", "palm", "tip", "") + "</robot>",
       "tip", "tip"},
      {"tip is the root", hand("j2", "revolute", ok_inner), "palm", "palm"},
      {"joint naming a missing child link",
       "<robot name='r'><link name='palm'/><link name='tip'/>" +
           joint("lost", "revolute", "palm", "nowhere", ok_inner) + "</robot>",
       "tip", "nowhere"},
      {"mimic of itself", hand("selfish", "revolute", ok_inner + "<mimic joint='selfish'/>"), "tip",
       "selfish"},
      {"links in a cycle (a fuzzed document: the walk to the root never ended)",
       "<robot name='r'><link name='palm'/><link name='a'/><link name='b'/>" +
           joint("ja", "revolute", "b", "a", ok_inner) +
           joint("jb", "revolute", "a", "b", ok_inner) + "</robot>",
       "a", "cycle"},
      {"negative fingertip sphere",
       "<robot name='r'><link name='palm'/><link name='tip'><collision><geometry>"
       "<sphere radius='-0.01'/></geometry></collision></link>" +
           joint("j1", "revolute", "palm", "tip", ok_inner) + "</robot>",
       "tip", "tip"},
      // urdfdom 3.0 uses the text of a malformed origin, radius, mass or material as a
      // printf format: '%s' there crashed the reader (a fuzzed document, the first below).
      {"'%' in an origin (printf format)",
       hand("j2", "revolute", "<origin xyz='%s%s%s%s%s%s%s%s'/>" + ok_inner), "tip", "'xyz'"},
      {"'%' in a fingertip radius",
       "<robot name='r'><link name='palm'/><link name='tip'><collision><geometry>"
       "<sphere radius='%n%n'/></geometry></collision></link>" +
           joint("j1", "revolute", "palm", "tip", ok_inner) + "</robot>",
       "tip", "'radius' of <sphere>"},
      {"'%' in a material name",
       hand("j2", "revolute", ok_inner, "<material name='red%s'><color rgba='1 0'/></material>"),
       "tip", "<material>"},
      {"'%' in element text", hand("j2", "revolute", ok_inner, "<note>50%</note>"), "tip",
       "text of <note>"},
      // tinyxml steps over the bytes a UTF-8 lead byte announces without looking for the
      // end of the text: a fuzzed document read past its buffer that way.
      {"a UTF-8 lead byte at the end of the text", hand("j2", "revolute", ok_inner) + "\xF0", "tip",
       "UTF-8"},
      {"a UTF-8 lead byte before a NUL",
       hand("j2", "revolute", ok_inner, "<note>\xE2" + std::string(1, '\0') + "</note>"), "tip",
       "UTF-8"},
      {"a lone 0xEF at the end (an unpatched tinyxml's line count loops)",
       hand("j2", "revolute", ok_inner) + "\xEF", "tip", "UTF-8"},
      {"an overlong '/' in a link name",
       hand("j2", "revolute", ok_inner, "<link name='a\xC0\xAF'/>"), "tip", "UTF-8"},
      {"a surrogate in a comment", hand("j2", "revolute", ok_inner, "<!-- \xED\xA0\x80 -->"), "tip",
       "UTF-8"},
      {"a Latin-1 byte in text", hand("j2", "revolute", ok_inner, "<note>M\xFCller</note>"), "tip",
       "UTF-8"},
  };
}

TEST(UrdfErrors, EachBadDocumentIsRefusedNamingTheElement) {
  int refused = 0;
  for (const BadCase& c : bad_cases()) {
    SCOPED_TRACE(c.what);
    const std::vector<FingerSpec> specs = {{"f", c.root, c.tip}};
    inhand::urdf::FingersResult<inhand::FingerChain<double, 3, inhand::Dynamic>> r;
    EXPECT_NO_THROW(r = inhand::urdf::read_fingers_string(c.xml, specs));
    EXPECT_FALSE(r.ok());
    EXPECT_TRUE(r.fingers.empty());
    EXPECT_NE(r.error.find(c.must_name), std::string::npos)
        << "error does not name '" << c.must_name << "': " << r.error;
    refused += r.ok() ? 0 : 1;
    std::cout << "[ refused  ] " << c.what << ": " << r.error << "\n";
  }
  EXPECT_EQ(refused, static_cast<int>(bad_cases().size()));
}

// A document that is not UTF-8 is refused naming the first offending byte and its line.
TEST(UrdfErrors, NotUtf8NamesTheByteAndItsLine) {
  const std::string xml = "<robot name='r'>\n<link name='palm'/>\n<!-- \xE2\x82 -->\n</robot>";
  const auto r = inhand::urdf::read_fingers_string(xml, {{"f", "palm", "tip"}});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error.find("byte 42 (line 3, 0xE2)"), std::string::npos) << r.error;
}

// Well-formed UTF-8 reads: a byte-order mark, and 2-, 3- and 4-byte characters in a
// comment, in text, and in the names of a link and a joint outside the finger.
TEST(UrdfErrors, Utf8DocumentsRead) {
  const std::string xml =
      "\xEF\xBB\xBF" + hand("j2", "revolute", kAxis + kLimit,
                            "<!-- Daumen \xC3\xBC, \xE2\x9C\x93, \xF0\x9D\x84\x9E -->"
                            "<note>\xC2\xB5m</note><link name='\xE6\x8C\x87'/>" +
                                joint("\xC3\xA9", "fixed", "palm", "\xE6\x8C\x87", ""));
  const auto r = inhand::urdf::read_fingers_string(xml, {{"f", "palm", "tip"}});
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.fingers[0].dof(), 2);
}

// The check against a decoder written the other way (the code point assembled from its
// bits, then its range checked): every string of one and two bytes, every three-byte
// string that starts with a lead byte, and seeded random four-byte strings
// (INHAND_URDF_UTF8_SAMPLES of them, default 200 000) agree on accepted or refused.
bool decodes_as_utf8(const std::string& s) {
  for (std::size_t i = 0; i < s.size();) {
    const auto b0 = static_cast<unsigned char>(s[i]);
    int n = b0 < 0x80 ? 1 : (b0 >> 5) == 0x6 ? 2 : (b0 >> 4) == 0xE ? 3 : (b0 >> 3) == 0x1E ? 4 : 0;
    if (n == 0 || b0 == 0 || i + static_cast<std::size_t>(n) > s.size()) return false;
    std::uint32_t cp = n == 1 ? b0 : (b0 & (0x7Fu >> n));
    for (int k = 1; k < n; ++k) {
      const auto c = static_cast<unsigned char>(s[i + static_cast<std::size_t>(k)]);
      if ((c >> 6) != 0x2) return false;
      cp = (cp << 6) | (c & 0x3Fu);
    }
    const std::uint32_t min_cp[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (cp < min_cp[n] || (cp >= 0xD800 && cp <= 0xDFFF) || cp > 0x10FFFF) return false;
    i += static_cast<std::size_t>(n);
  }
  return true;
}

TEST(UrdfErrors, Utf8CheckAgreesWithADecoder) {
  using inhand::urdf::detail::find_invalid_utf8;
  long checked = 0, accepted = 0;
  const auto agree = [&](const std::string& s) {
    const bool valid = decodes_as_utf8(s);
    accepted += valid ? 1 : 0;
    ++checked;
    if (find_invalid_utf8(s).empty() == valid) return true;
    ADD_FAILURE() << "disagree on " << ::testing::PrintToString(s) << " (decoder: " << valid << ")";
    return false;
  };
  for (int a = 0; a < 256; ++a) {
    if (!agree(std::string(1, static_cast<char>(a)))) return;
    for (int b = 0; b < 256; ++b) {
      const std::string two{static_cast<char>(a), static_cast<char>(b)};
      if (!agree(two)) return;
      if (a < 0xC0) continue;
      for (int c = 0; c < 256; ++c)
        if (!agree(two + static_cast<char>(c))) return;
    }
  }
  const char* env = std::getenv("INHAND_URDF_UTF8_SAMPLES");
  const long samples = env != nullptr ? std::atol(env) : 200000;
  std::mt19937 rng(15);
  std::uniform_int_distribution<int> lead(0xF0, 0xF7), cont(0x70, 0xC7);
  for (long i = 0; i < samples; ++i) {
    const std::string four{static_cast<char>(lead(rng)), static_cast<char>(cont(rng)),
                           static_cast<char>(cont(rng)), static_cast<char>(cont(rng))};
    if (!agree(four)) return;
  }
  std::cout << "[ utf-8    ] " << checked << " strings, " << accepted << " well-formed\n";
  EXPECT_GT(accepted, 0);
}

// A tip link on another branch of the tree: the error names both links.
TEST(UrdfErrors, TipNotBelowRootNamesBothLinks) {
  const std::string xml = hand("j2", "revolute", kAxis + kLimit,
                               "<link name='other'/>" + joint("jo", "fixed", "palm", "other", ""));
  const auto r = inhand::urdf::read_fingers_string(xml, {{"f", "l2", "other"}});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error.find("'other'"), std::string::npos) << r.error;
  EXPECT_NE(r.error.find("'l2'"), std::string::npos) << r.error;
}

// A missing file is an error naming the path, not an exception.
TEST(UrdfErrors, MissingFileNamesThePath) {
  const auto r = inhand::urdf::read_fingers_file("/nonexistent/hand.urdf", {{"f", "palm", "tip"}});
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error.find("/nonexistent/hand.urdf"), std::string::npos) << r.error;
}

// A '%' where urdfdom never formats it reads: a mesh's (URL-escaped) filename, a comment.
TEST(UrdfErrors, PercentInAMeshFilenameOrACommentReads) {
  const std::string xml = hand("j2", "revolute", kAxis + kLimit,
                               "<!-- 50% scale --><link name='shell'><visual><geometry>"
                               "<mesh filename='package://hand/my%20mesh.stl'/></geometry>"
                               "</visual></link>" +
                                   joint("js", "fixed", "palm", "shell", ""));
  const auto r = inhand::urdf::read_fingers_string(xml, {{"f", "palm", "tip"}});
  ASSERT_TRUE(r.ok()) << r.error;
  EXPECT_EQ(r.fingers[0].dof(), 2);
}

// The good document of the table reads, with the continuous-joint and default-velocity
// conventions, a mimic coupling, and the spec's fingertip where the tip has no sphere.
TEST(UrdfErrors, TheGoodDocumentReads) {
  const std::string xml = hand(
      "j2", "continuous", "<axis xyz='0 0 2'/><mimic joint='j1' multiplier='-0.5' offset='0.1'/>");
  FingerSpec spec{"f", "palm", "tip"};
  spec.fingertip_radius = 0.007;
  spec.contact_offset = Eigen::Vector3d(0, 0, 0.003);
  inhand::urdf::ReadOptions options;
  options.default_velocity = 1.5;
  const auto r = inhand::urdf::read_fingers_string(xml, {spec}, options);
  ASSERT_TRUE(r.ok()) << r.error;
  const auto& c = r.fingers[0];
  ASSERT_EQ(c.dof(), 2);
  EXPECT_EQ(c.joints[1].axis, Eigen::Vector3d::UnitZ());
  EXPECT_EQ(c.joints[1].lower, -options.continuous_limit);
  EXPECT_EQ(c.joints[1].upper, options.continuous_limit);
  EXPECT_EQ(c.joints[1].max_velocity, 1.5);
  EXPECT_EQ(c.joints[0].max_velocity, 1.0);
  EXPECT_EQ(c.joints[1].coupling.leader, 0);
  EXPECT_EQ(c.joints[1].coupling.ratio, -0.5);
  EXPECT_EQ(c.joints[1].coupling.offset, 0.1);
  EXPECT_EQ(c.fingertip_radius, 0.007);
  EXPECT_EQ(c.joint_to_tip.position, Eigen::Vector3d(0, 0, 0.003));
  EXPECT_EQ(r.joint_names[0], (std::vector<std::string>{"j1", "j2"}));
}

}  // namespace
