// Gmsh MSH 4.1 sections: $Entities, $Nodes (entity blocks, parametric
// coordinates) and $Elements. ASCII and binary files list the same values in
// the same order, so one code path reads both through Cursor::get_*; only the
// binary header lines need end_line() before the data.
#include <array>

#include "curvemesh/io/msh_common.hpp"

namespace cm::io::msh {

namespace {

constexpr std::array<const char*, 4> kEntityCountNames{"number of points", "number of curves",
                                                       "number of surfaces", "number of volumes"};

void parse_entities(Cursor& c, RawMesh& raw) {
  if (c.binary()) c.end_line();
  std::array<std::uint64_t, 4> counts{};
  for (int d = 0; d < 4; ++d) counts[d] = c.get_size(kEntityCountNames[d]);
  // A point is at least tag, x, y, z, #physicals; a curve, surface or volume
  // tag, a 6-value box, #physicals, #bounding.
  for (int d = 0; d < 4; ++d)
    c.check_count(counts[d], d == 0 ? 5 : 9, d == 0 ? 36 : 68, kEntityCountNames[d]);
  std::vector<mesh::EntityInfo> entities;
  for (int d = 0; d < 4; ++d)
    for (std::uint64_t i = 0; i < counts[d]; ++i) {
      mesh::EntityInfo e;
      e.dim = d;
      e.tag = c.get_int("entity tag");
      // The point position / bounding box is the model's; the mesh has its own.
      for (int k = 0; k < (d == 0 ? 3 : 6); ++k) c.get_double("entity bounding box", false);
      const std::uint64_t num_physicals = c.get_size("number of physical tags");
      c.check_count(num_physicals, 1, 4, "number of physical tags");
      for (std::uint64_t k = 0; k < num_physicals; ++k)
        e.physicals.push_back(c.get_int("physical tag"));
      if (d > 0) {
        const std::uint64_t num_bounding = c.get_size("number of bounding entities");
        c.check_count(num_bounding, 1, 4, "number of bounding entities");
        for (std::uint64_t k = 0; k < num_bounding; ++k)
          e.bounding.push_back(c.get_int("bounding entity tag"));
      }
      entities.push_back(std::move(e));
    }
  c.expect_token("$EndEntities");
  raw.entities = std::move(entities);
}

void parse_nodes(Cursor& c, RawMesh& raw) {
  if (c.binary()) c.end_line();
  const std::uint64_t num_blocks = c.get_size("number of node blocks");
  const std::uint64_t num_nodes = c.get_size("number of nodes");
  c.get_size("minimum node tag");
  c.get_size("maximum node tag");
  const Position header = c.position();
  c.check_count(num_blocks, 4, 20, "number of node blocks");
  c.check_count(num_nodes, 4, 32, "number of nodes");
  RawNodes& nodes = raw.nodes;
  nodes.map.reserve(num_nodes);
  nodes.tags.reserve(num_nodes);
  nodes.coords.reserve(num_nodes);
  nodes.entity.reserve(num_nodes);
  nodes.param.reserve(num_nodes);

  std::vector<std::uint64_t> tags;
  std::vector<Position> tag_pos;
  std::uint64_t total = 0;
  for (std::uint64_t b = 0; b < num_blocks; ++b) {
    const mesh::ModelRef entity{c.get_int("entity dimension", 0, 3), 0};
    const std::int32_t entity_tag = c.get_int("entity tag");
    const bool parametric = c.get_int("parametric flag", 0, 1) == 1;
    const std::uint64_t n = c.get_size("number of nodes in the block");
    const int num_params = parametric ? entity.dim : 0;
    c.check_count(n, 4 + static_cast<std::uint64_t>(num_params),
                  8 + 8 * (3 + static_cast<std::uint64_t>(num_params)),
                  "number of nodes in the block");
    if (n > num_nodes - total)
      c.fail(fmt::format(
          "the node blocks hold more nodes than the {} announced in the $Nodes header", num_nodes));
    total += n;
    tags.resize(n);
    tag_pos.resize(n);
    for (std::uint64_t k = 0; k < n; ++k) {
      tags[k] = c.get_size("node tag");
      tag_pos[k] = c.position();
    }
    const mesh::ModelRef ref{entity.dim, entity_tag};
    for (std::uint64_t k = 0; k < n; ++k) {
      Vec3 x;
      for (int j = 0; j < 3; ++j) x[j] = c.get_double("node coordinate");
      mesh::Param param;
      if (num_params >= 1) param.u = c.get_double("parametric coordinate");
      if (num_params >= 2) param.v = c.get_double("parametric coordinate");
      // A volume node's (u, v, w) is its position again: nothing to keep.
      if (num_params == 3) c.get_double("parametric coordinate");
      nodes.add(c, tag_pos[k], tags[k], x, ref, param);
    }
  }
  if (total != num_nodes)
    c.fail_at(header, fmt::format("the $Nodes header announces {} nodes but its blocks hold {}",
                                  num_nodes, total));
  c.expect_token("$EndNodes");
}

void parse_elements(Cursor& c, RawMesh& raw) {
  if (c.binary()) c.end_line();
  const std::uint64_t num_blocks = c.get_size("number of element blocks");
  const std::uint64_t num_elements = c.get_size("number of elements");
  c.get_size("minimum element tag");
  c.get_size("maximum element tag");
  const Position header = c.position();
  c.check_count(num_blocks, 4, 20, "number of element blocks");
  c.check_count(num_elements, 2, 16, "number of elements");

  std::array<std::uint64_t, 20> node_tags{};
  std::uint64_t total = 0;
  for (std::uint64_t b = 0; b < num_blocks; ++b) {
    const int dim = c.get_int("entity dimension", 0, 3);
    const std::int32_t entity_tag = c.get_int("entity tag");
    const std::int32_t type_number = c.get_int("element type");
    const ElementType* type = find_element_type(type_number);
    if (!type) c.fail(unsupported_type_message(type_number));
    if (kind_dim(type->kind) != dim)
      c.fail(fmt::format("element type {} has dimension {} but its block's entity has dimension {}",
                         type_number, kind_dim(type->kind), dim));
    const std::uint64_t n = c.get_size("number of elements in the block");
    const auto per_element = static_cast<std::uint64_t>(1 + type->num_nodes);
    c.check_count(n, per_element, 8 * per_element, "number of elements in the block");
    if (n > num_elements - total)
      c.fail(fmt::format(
          "the element blocks hold more elements than the {} announced in the $Elements header",
          num_elements));
    total += n;
    RawElements& elements = raw.begin_elements(c, *type);
    for (std::uint64_t i = 0; i < n; ++i) {
      const std::uint64_t tag = c.get_size("element tag");
      const Position pos = c.position();
      for (int k = 0; k < type->num_nodes; ++k)
        node_tags[static_cast<std::size_t>(k)] = c.get_size("node tag");
      raw.add_element(c, elements, tag, entity_tag, node_tags.data(), pos);
    }
  }
  if (total != num_elements)
    c.fail_at(header,
              fmt::format("the $Elements header announces {} elements but its blocks hold {}",
                          num_elements, total));
  c.expect_token("$EndElements");
}

}  // namespace

void parse_msh41(Cursor& c, RawMesh& raw) {
  bool seen_entities = false, seen_nodes = false, seen_elements = false;
  const auto once = [&](bool& seen, std::string_view name) {
    if (seen) c.fail(fmt::format("duplicate {} section", name));
    seen = true;
  };
  while (!c.at_end()) {
    const std::string_view name = c.next_token("a section name");
    if (name == "$Entities") {
      once(seen_entities, name);
      parse_entities(c, raw);
    } else if (name == "$Nodes") {
      once(seen_nodes, name);
      parse_nodes(c, raw);
    } else if (name == "$Elements") {
      once(seen_elements, name);
      if (!seen_nodes) c.fail("$Elements section before the $Nodes section");
      parse_elements(c, raw);
    } else if (name == "$PartitionedEntities") {
      // Its node and element blocks would refer to partition entities, not to
      // the model's, and the classification would be wrong.
      c.fail("partitioned meshes ($PartitionedEntities) are not supported");
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
