// Gmsh MSH 2.2 (and 2.0/2.1, the same layout) sections $Nodes and $Elements,
// ASCII and binary. The format has no entities: an element's region, face or
// edge tag is its elementary tag (its second tag), vertices stay unclassified
// except for nodes of point elements, and m.entities lists every (dim,
// elementary tag) used with the physical tags (first tag) seen on it.
#include <algorithm>
#include <array>
#include <tuple>

#include "curvemesh/io/msh_common.hpp"

namespace cm::io::msh {

namespace {

void parse_nodes(Cursor& c, RawMesh& raw) {
  const auto n = static_cast<std::uint64_t>(c.text_int("number of nodes", 0, INT64_MAX));
  if (c.binary()) c.end_line();
  // Text: tag x y z; binary: int32 tag and three doubles.
  c.check_count(n, 4, 28, "number of nodes");
  RawNodes& nodes = raw.nodes;
  nodes.map.reserve(n);
  nodes.tags.reserve(n);
  nodes.coords.reserve(n);
  nodes.entity.reserve(n);
  nodes.param.reserve(n);
  for (std::uint64_t i = 0; i < n; ++i) {
    const std::uint64_t tag =
        c.binary() ? static_cast<std::uint64_t>(c.get_int("node tag", 0, INT32_MAX))
                   : static_cast<std::uint64_t>(c.text_int("node tag", 0, INT64_MAX));
    const Position pos = c.position();
    Vec3 x;
    for (int j = 0; j < 3; ++j) x[j] = c.get_double("node coordinate");
    nodes.add(c, pos, tag, x, mesh::ModelRef{}, mesh::Param{});
  }
  c.expect_token("$EndNodes");
}

// (dim, elementary tag, physical tag) of every element, for m.entities.
using EntityUse = std::tuple<int, std::int32_t, std::int32_t>;

struct ElementTags {
  std::int32_t physical = 0;
  std::int32_t elementary = 0;
};

// The first tag is the physical group, the second the elementary entity; a
// lone tag is taken as the entity (some writers emit only that).
ElementTags interpret_tags(const std::array<std::int64_t, 2>& first_two, std::int64_t count) {
  if (count >= 2)
    return {static_cast<std::int32_t>(first_two[0]), static_cast<std::int32_t>(first_two[1])};
  if (count == 1) return {0, static_cast<std::int32_t>(first_two[0])};
  return {};
}

void record_use(std::vector<EntityUse>& uses, const ElementType& type, const ElementTags& tags) {
  const EntityUse use{kind_dim(type.kind), tags.elementary, tags.physical};
  if (uses.empty() || uses.back() != use) uses.push_back(use);
}

void parse_text_elements(Cursor& c, RawMesh& raw, std::uint64_t n, std::vector<EntityUse>& uses) {
  std::array<std::uint64_t, 20> node_tags{};
  for (std::uint64_t i = 0; i < n; ++i) {
    const auto tag = static_cast<std::uint64_t>(c.text_int("element tag", 0, INT64_MAX));
    const Position pos = c.position();
    const auto type_number = c.text_int("element type", INT32_MIN, INT32_MAX);
    const ElementType* type = find_element_type(static_cast<int>(type_number));
    if (!type) c.fail(unsupported_type_message(type_number));
    const auto num_tags = c.text_int("number of tags", 0, INT32_MAX);
    std::array<std::int64_t, 2> first_two{};
    for (std::int64_t k = 0; k < num_tags; ++k) {
      const auto value = c.text_int("element tag value", INT32_MIN, INT32_MAX);
      if (k < 2) first_two[static_cast<std::size_t>(k)] = value;
    }
    const ElementTags tags = interpret_tags(first_two, num_tags);
    RawElements& elements = raw.begin_elements(c, *type);
    for (int k = 0; k < type->num_nodes; ++k)
      node_tags[static_cast<std::size_t>(k)] =
          static_cast<std::uint64_t>(c.text_int("node tag", 0, INT64_MAX));
    raw.add_element(c, elements, tag, tags.elementary, node_tags.data(), pos);
    record_use(uses, *type, tags);
  }
}

// Binary: groups of elements of one type and tag count, each group headed by
// (type, number of elements, number of tags) as int32.
void parse_binary_elements(Cursor& c, RawMesh& raw, std::uint64_t n, std::vector<EntityUse>& uses) {
  std::array<std::uint64_t, 20> node_tags{};
  std::uint64_t done = 0;
  while (done < n) {
    const std::int32_t type_number = c.get_int("element type");
    const ElementType* type = find_element_type(type_number);
    if (!type) c.fail(unsupported_type_message(type_number));
    const auto count =
        static_cast<std::uint64_t>(c.get_int("number of elements in the group", 1, INT32_MAX));
    if (count > n - done)
      c.fail(fmt::format("the element groups hold more elements than the {} announced in $Elements",
                         n));
    const auto num_tags = static_cast<std::uint64_t>(c.get_int("number of tags", 0, INT32_MAX));
    const std::uint64_t per_element = 1 + num_tags + static_cast<std::uint64_t>(type->num_nodes);
    c.check_count(count, 0, 4 * per_element, "number of elements in the group");
    RawElements& elements = raw.begin_elements(c, *type);
    for (std::uint64_t i = 0; i < count; ++i) {
      const auto tag = static_cast<std::uint64_t>(c.get_int("element tag", 0, INT32_MAX));
      const Position pos = c.position();
      std::array<std::int64_t, 2> first_two{};
      for (std::uint64_t k = 0; k < num_tags; ++k) {
        const std::int32_t value = c.get_int("element tag value");
        if (k < 2) first_two[k] = value;
      }
      const ElementTags tags = interpret_tags(first_two, static_cast<std::int64_t>(num_tags));
      for (int k = 0; k < type->num_nodes; ++k)
        node_tags[static_cast<std::size_t>(k)] =
            static_cast<std::uint64_t>(c.get_int("node tag", 0, INT32_MAX));
      raw.add_element(c, elements, tag, tags.elementary, node_tags.data(), pos);
      record_use(uses, *type, tags);
    }
    done += count;
  }
}

void parse_elements(Cursor& c, RawMesh& raw) {
  const auto n = static_cast<std::uint64_t>(c.text_int("number of elements", 0, INT64_MAX));
  if (c.binary()) c.end_line();
  // At least tag, type, #tags and one node (text) / tag and one node (binary).
  c.check_count(n, 4, 8, "number of elements");
  std::vector<EntityUse> uses;
  if (c.binary())
    parse_binary_elements(c, raw, n, uses);
  else
    parse_text_elements(c, raw, n, uses);
  c.expect_token("$EndElements");

  std::sort(uses.begin(), uses.end());
  uses.erase(std::unique(uses.begin(), uses.end()), uses.end());
  for (const auto& [dim, tag, physical] : uses) {
    if (raw.entities.empty() || raw.entities.back().dim != dim || raw.entities.back().tag != tag) {
      mesh::EntityInfo e;
      e.dim = dim;
      e.tag = tag;
      raw.entities.push_back(std::move(e));
    }
    if (physical != 0) raw.entities.back().physicals.push_back(physical);
  }
}

}  // namespace

void parse_msh22(Cursor& c, RawMesh& raw) {
  bool seen_nodes = false, seen_elements = false;
  const auto once = [&](bool& seen, std::string_view name) {
    if (seen) c.fail(fmt::format("duplicate {} section", name));
    seen = true;
  };
  while (!c.at_end()) {
    const std::string_view name = c.next_token("a section name");
    if (name == "$Nodes") {
      once(seen_nodes, name);
      parse_nodes(c, raw);
    } else if (name == "$Elements") {
      once(seen_elements, name);
      if (!seen_nodes) c.fail("$Elements section before the $Nodes section");
      parse_elements(c, raw);
    } else if (name.size() > 1 && name[0] == '$' && !name.starts_with("$End")) {
      c.skip_section(name);
    } else {
      c.fail(fmt::format("expected a section name such as $Nodes, got {}", quote(name)));
    }
  }
  if (!seen_nodes) c.fail("missing $Nodes section");
  if (!seen_elements) c.fail("missing $Elements section");
}

}  // namespace cm::io::msh
