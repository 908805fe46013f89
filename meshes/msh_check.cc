#include "meshes/msh_check.h"

#include <cmath>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace fetouch::meshes {

namespace {

constexpr double kMaxNodes = 5e7, kMaxElements = 3e8;

// Nodes per element of Gmsh's element types (0: not a type read here).
int nodes_of(long type) {
  static const std::map<long, int> nodes{{1, 2},  {2, 3},  {3, 4},  {4, 4},   {5, 8},  {6, 6},  {7, 5},  {8, 3},
                                         {9, 6},  {10, 9}, {11, 10}, {12, 27}, {13, 18}, {14, 14}, {15, 1}, {17, 20},
                                         {29, 20}};
  const auto found = nodes.find(type);
  return found == nodes.end() ? 0 : found->second;
}

class MshLines {
 public:
  explicit MshLines(const std::filesystem::path& path) : name_(path.string()), in_(path, std::ios::binary) {}

  [[noreturn]] void fail(const std::string& what) const {
    throw std::runtime_error(name_ + ":" + std::to_string(line_) + ": " + what);
  }
  // The next line's words; fails at the end of the file (`what` was expected there).
  std::istringstream& next(const std::string& what) {
    if (!std::getline(in_, text_)) fail("the file ends where " + what + " was expected");
    ++line_;
    if (!text_.empty() && text_.back() == '\r') text_.pop_back();
    words_.clear();
    words_.str(text_);
    return words_;
  }
  bool at_end() { return in_.peek() == std::char_traits<char>::eof(); }
  const std::string& text() const { return text_; }

  // `n` whole numbers from the current line, each within [low, high].
  std::vector<long> whole(std::size_t n, double low, double high, const std::string& what) {
    std::vector<long> out;
    for (std::size_t i = 0; i < n; ++i) {
      double x;
      if (!(words_ >> x) || x != std::floor(x) || x < low || x > high) fail("expected " + what + ", found '" + shown() + "'");
      out.push_back(static_cast<long>(x));
    }
    return out;
  }
  void finite(std::size_t n, const std::string& what) {
    for (std::size_t i = 0; i < n; ++i) {
      double x;
      if (!(words_ >> x) || !std::isfinite(x)) fail("expected " + what + ", found '" + shown() + "'");
    }
  }
  void end_of_line(const std::string& what) {
    std::string extra;
    if (words_ >> extra) fail("more than " + what + " on the line: '" + shown() + "'");
  }
  void expect(const std::string& marker) {
    next(marker);
    if (text_ != marker) fail("expected " + marker + ", found '" + shown() + "'");
  }
  std::string shown() const {
    std::string out = text_.size() <= 60 ? text_ : text_.substr(0, 57) + "...";
    for (char& c : out)
      if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) >= 0x7f) c = '?';
    return out;
  }

 private:
  std::string name_;
  std::ifstream in_;
  std::string text_;
  std::istringstream words_;
  long line_ = 0;
};

}  // namespace

void check_msh_structure(const std::filesystem::path& path) {
  MshLines in(path);
  in.expect("$MeshFormat");
  auto& format = in.next("the version line");
  std::string version;
  format >> version;
  if (version != "4.1" && version != "2.2") in.fail("MSH version '" + version + "'; Fetouch reads ASCII MSH 4.1 and 2.2");
  const long file_type = in.whole(1, 0, 1, "the file type 0 (ASCII)")[0];
  if (file_type != 0) in.fail("a binary MSH file; save it as ASCII (gmsh FILE -format msh41 -save_ascii -0)");
  in.whole(1, 8, 8, "the data size 8");
  in.end_of_line("three values");
  in.expect("$EndMeshFormat");
  const bool v4 = version == "4.1";

  std::set<std::pair<long, long>> entities;  // (dim, tag)
  std::vector<bool> node;                    // defined node tags
  bool have_entities = false, have_nodes = false, have_elements = false;
  while (!in.at_end()) {
    in.next("a section");
    if (in.text().empty()) continue;
    if (in.text()[0] != '$') in.fail("expected a section ($Name), found '" + in.shown() + "'");
    const std::string name = in.text().substr(1);
    if (name == "PhysicalNames") {
      in.next("the number of physical names");
      const long n = in.whole(1, 0, 1e6, "the number of physical names")[0];
      for (long i = 0; i < n; ++i) {
        in.next("a physical name");
        in.whole(1, 0, 3, "a dimension from 0 to 3");
        in.whole(1, 1, 2147483647, "a positive physical tag");
        const auto open = in.text().find('"'), close = in.text().rfind('"');
        if (open == std::string::npos || close == open) in.fail("expected a quoted name, found '" + in.shown() + "'");
      }
    } else if (name == "Entities" && v4) {
      in.next("the entity counts");
      const auto n = in.whole(4, 0, 1e7, "four entity counts");
      for (int dim = 0; dim < 4; ++dim)
        for (long i = 0; i < n[dim]; ++i) {
          in.next("an entity");
          const long tag = in.whole(1, 1, 2147483647, "a positive entity tag")[0];
          in.finite(dim == 0 ? 3 : 6, "its coordinates");
          const long physicals = in.whole(1, 0, 1e6, "the number of physical tags")[0];
          in.whole(static_cast<std::size_t>(physicals), -2147483647, 2147483647, "physical tags");
          if (dim > 0) {
            const long bounding = in.whole(1, 0, 1e7, "the number of bounding entities")[0];
            in.whole(static_cast<std::size_t>(bounding), -2147483647, 2147483647, "bounding entity tags");
          }
          in.end_of_line("the entity's values");
          entities.insert({dim, tag});
        }
      have_entities = true;
    } else if (name == "Nodes") {
      if (v4 && !have_entities) in.fail("$Nodes before $Entities (MSH 4.1 needs $Entities first)");
      in.next("the node counts");
      if (v4) {
        const auto h = in.whole(4, 0, 2147483647, "four numbers: blocks, nodes, smallest and largest tag");
        if (h[1] > kMaxNodes || h[3] > kMaxNodes * 4) in.fail(std::to_string(h[1]) + " nodes; at most 5 * 10^7");
        node.assign(static_cast<std::size_t>(h[3]) + 1, false);
        long total = 0;
        for (long b = 0; b < h[0]; ++b) {
          in.next("a node block");
          const auto block = in.whole(4, 0, 2147483647, "a node block: dimension, entity, parametric, count");
          if (block[0] > 3 || block[2] != 0) in.fail("a node block of dimension 0 to 3 without parametric coordinates expected");
          if (!entities.count({block[0], block[1]})) in.fail("nodes on entity (" + std::to_string(block[0]) + ", " + std::to_string(block[1]) + "), which $Entities does not define");
          if ((total += block[3]) > h[1]) in.fail("more nodes than the " + std::to_string(h[1]) + " declared");
          for (long i = 0; i < block[3]; ++i) {
            in.next("a node tag");
            const long tag = in.whole(1, static_cast<double>(h[2]), static_cast<double>(h[3]), "a node tag within the declared range")[0];
            node[static_cast<std::size_t>(tag)] = true;
          }
          for (long i = 0; i < block[3]; ++i) {
            in.next("node coordinates");
            in.finite(3, "three finite coordinates");
            in.end_of_line("three coordinates");
          }
        }
        if (total != h[1]) in.fail(std::to_string(total) + " nodes where " + std::to_string(h[1]) + " were declared");
      } else {
        const long n = in.whole(1, 0, kMaxNodes, "the number of nodes (at most 5 * 10^7)")[0];
        for (long i = 0; i < n; ++i) {
          in.next("a node");
          const long tag = in.whole(1, 1, kMaxNodes * 4, "a positive node tag")[0];
          in.finite(3, "three finite coordinates");
          in.end_of_line("a tag and three coordinates");
          if (static_cast<std::size_t>(tag) >= node.size()) node.resize(static_cast<std::size_t>(tag) + 1, false);
          node[static_cast<std::size_t>(tag)] = true;
        }
      }
      in.expect("$EndNodes");
      have_nodes = true;
      continue;
    } else if (name == "Elements") {
      if (!have_nodes) in.fail("$Elements before $Nodes");
      in.next("the element counts");
      const auto defined = [&](long tag) { return tag >= 0 && static_cast<std::size_t>(tag) < node.size() && node[static_cast<std::size_t>(tag)]; };
      if (v4) {
        const auto h = in.whole(4, 0, 2147483647, "four numbers: blocks, elements, smallest and largest tag");
        if (h[1] > kMaxElements) in.fail(std::to_string(h[1]) + " elements; at most 3 * 10^8");
        long total = 0;
        for (long b = 0; b < h[0]; ++b) {
          in.next("an element block");
          const auto block = in.whole(4, 0, 2147483647, "an element block: dimension, entity, type, count");
          const int corners = nodes_of(block[2]);
          if (block[0] > 3 || corners == 0) in.fail("element type " + std::to_string(block[2]) + " of dimension " + std::to_string(block[0]) + " is not one Gmsh defines");
          if (!entities.count({block[0], block[1]})) in.fail("elements on entity (" + std::to_string(block[0]) + ", " + std::to_string(block[1]) + "), which $Entities does not define");
          if ((total += block[3]) > h[1]) in.fail("more elements than the " + std::to_string(h[1]) + " declared");
          for (long i = 0; i < block[3]; ++i) {
            in.next("an element");
            in.whole(1, static_cast<double>(h[2]), static_cast<double>(h[3]), "an element tag within the declared range");
            for (const long tag : in.whole(static_cast<std::size_t>(corners), 1, 2147483647, std::to_string(corners) + " node tags"))
              if (!defined(tag)) in.fail("the element names node " + std::to_string(tag) + ", which $Nodes does not define");
            in.end_of_line("a tag and " + std::to_string(corners) + " nodes");
          }
        }
        if (total != h[1]) in.fail(std::to_string(total) + " elements where " + std::to_string(h[1]) + " were declared");
      } else {
        const long n = in.whole(1, 0, kMaxElements, "the number of elements")[0];
        for (long i = 0; i < n; ++i) {
          in.next("an element");
          const auto e = in.whole(3, 0, 2147483647, "an element: tag, type, number of tags");
          const int corners = nodes_of(e[1]);
          if (corners == 0) in.fail("element type " + std::to_string(e[1]) + " is not one Gmsh defines");
          in.whole(static_cast<std::size_t>(e[2]), -2147483647, 2147483647, "its tags");
          for (const long tag : in.whole(static_cast<std::size_t>(corners), 1, 2147483647, std::to_string(corners) + " node tags"))
            if (!defined(tag)) in.fail("the element names node " + std::to_string(tag) + ", which $Nodes does not define");
          in.end_of_line("the element's values");
        }
      }
      in.expect("$EndElements");
      have_elements = true;
      continue;
    } else if (name.rfind("End", 0) == 0) {
      in.fail("'" + in.shown() + "' closes no open section");
    } else {
      // A section read as it is ($PartitionedEntities, $Periodic, $NodeData, ...): closed by $EndName.
      for (;;) {
        in.next("$End" + name);
        if (in.text() == "$End" + name) break;
        if (!in.text().empty() && in.text()[0] == '$' && in.text() != "$End" + name && in.text().rfind("$End", 0) == 0)
          in.fail("expected $End" + name + ", found '" + in.shown() + "'");
      }
      continue;
    }
    in.expect("$End" + name);
  }
  if (!have_nodes || !have_elements) in.fail("no " + std::string(have_nodes ? "$Elements" : "$Nodes") + " section: not a mesh");
}

}  // namespace fetouch::meshes
