// Semantic checks of mission.json: areas, keep-out zones, priors and scene relations.
#include "validation_internal.h"

namespace hameritt::scenario::validation_internal {

void Semantics::mission() {
  scenarioId(doc_, "/scenario_id");

  IdSet targets(this, "objective target id");
  if (const json* obj = member(doc_, "objective")) {
    const json& ts = arrayOrEmpty(*obj, "targets");
    for (std::size_t i = 0; i < ts.size(); ++i)
      targets.note(ts[i], "/objective/targets/" + std::to_string(i));
  }

  IdSet aoi_ids(this, "area of interest id");
  std::map<std::string, Polygon> aois;
  const json& aoi_list = arrayOrEmpty(doc_, "areas_of_interest");
  for (std::size_t i = 0; i < aoi_list.size(); ++i) {
    const std::string p = jsonPointerAppend("/areas_of_interest", i);
    aoi_ids.note(aoi_list[i], p);
    const json* poly = member(aoi_list[i], "polygon");
    std::optional<Polygon> pg = poly ? polygon(*poly, p + "/polygon") : std::nullopt;
    if (pg && stringAt(aoi_list[i], "id")) aois.emplace(*stringAt(aoi_list[i], "id"), *pg);
    timeWindow(aoi_list[i], p);
  }

  IdSet koz_ids(this, "keep-out zone id");
  const json& kozs = arrayOrEmpty(doc_, "keep_out_zones");
  for (std::size_t i = 0; i < kozs.size(); ++i) {
    const std::string p = jsonPointerAppend("/keep_out_zones", i);
    koz_ids.note(kozs[i], p);
    if (const json* poly = member(kozs[i], "polygon")) polygon(*poly, p + "/polygon");
    if (const json* alt = member(kozs[i], "altitude")) altitude(*alt, p + "/altitude");
    timeWindow(kozs[i], p);
    if (member(kozs[i], "motion")) trajectoryOrder(arrayOrEmpty(kozs[i], "motion"), p + "/motion");
  }

  priors(aoi_ids, aois);

  IdSet route_ids(this, "route id");
  const json& routes = arrayOrEmpty(doc_, "routes");
  for (std::size_t i = 0; i < routes.size(); ++i) {
    const std::string p = jsonPointerAppend("/routes", i);
    route_ids.note(routes[i], p);
    if (const json* band = member(routes[i], "band_polygon")) polygon(*band, p + "/band_polygon");
    std::vector<Vec2> line;
    if (const json* pl = member(routes[i], "polyline"); pl && toPoints(*pl, &line)) {
      for (std::size_t k = 1; k < line.size(); ++k) {
        if (line[k] == line[k - 1]) {
          add(jsonPointerAppend(p + "/polyline", k), "route_polyline",
              "point repeats the previous one");
        }
      }
    }
  }

  relations(targets);

  // Phases: unique ids, targets that the objective names, a search only as the first phase.
  IdSet phase_ids(this, "phase id");
  const json& phases = arrayOrEmpty(doc_, "phases");
  for (std::size_t i = 0; i < phases.size(); ++i) {
    const std::string p = jsonPointerAppend("/phases", i);
    phase_ids.note(phases[i], p);
    const json& ts = arrayOrEmpty(phases[i], "targets");
    for (std::size_t k = 0; k < ts.size(); ++k) {
      if (ts[k].is_string() && !targets.has(ts[k].get<std::string>())) {
        add(jsonPointerAppend(p + "/targets", k), "phase_target",
            "'" + ts[k].get<std::string>() + "' is not an objective target id");
      }
    }
    if (i > 0 && stringAt(phases[i], "type") == std::optional<std::string>("search")) {
      add(p + "/type", "phase_order", "a search phase can only be the first phase");
    }
  }
  // An avoid mission says where to fly: an avoid phase with its goal and criteria.
  if (stringAt(doc_, "class") == std::optional<std::string>("avoid")) {
    bool has_avoid = false;
    for (const auto& ph : phases) {
      has_avoid = has_avoid || stringAt(ph, "type") == std::optional<std::string>("avoid");
    }
    if (!has_avoid) add("/phases", "avoid_phase", "an avoid mission needs an avoid phase");
  }
  // A follow mission finds its target, then follows it; a track mission finds its targets, then
  // keeps them in view: phases search and then follow (track) of the same targets, the second
  // phase (with a follow phase's approach allowance) shorter than the time limit.
  for (const std::string cls : {"follow", "track"}) {
    if (stringAt(doc_, "class") != std::optional<std::string>(cls)) continue;
    const std::string rule = cls + "_phase";
    const auto type = [&](std::size_t i) { return stringAt(phases[i], "type"); };
    if (phases.size() != 2 || type(0) != std::optional<std::string>("search") ||
        type(1) != std::optional<std::string>(cls)) {
      add("/phases", rule, "a " + cls + " mission needs two phases: search, then " + cls);
      continue;
    }
    if (phases[0].contains("targets") && phases[1].contains("targets") &&
        phases[0]["targets"] != phases[1]["targets"]) {
      add("/phases/1/targets", rule, "expected the search phase's targets");
    }
    const json* d = member(phases[1], "duration");
    const json* limit = member(doc_, "time_limit");
    const json* c = member(phases[1], "criteria");
    const json* a = c ? member(*c, "approach_s") : nullptr;
    const double approach = a && a->is_number() ? a->get<double>() : 0.0;
    if (d && limit && d->is_number() && limit->is_number() &&
        !(d->get<double>() + approach < limit->get<double>())) {
      add("/phases/1/duration", rule,
          "expected duration + criteria.approach_s less than the mission's time_limit");
    }
  }
}

void Semantics::priors(const IdSet& aoi_ids, const std::map<std::string, Polygon>& aois) {
  IdSet cell_ids(this, "prior cell id");
  std::set<std::string> covered;
  const json& priors = arrayOrEmpty(doc_, "area_priors");
  for (std::size_t i = 0; i < priors.size(); ++i) {
    const json& pr = priors[i];
    const std::string p = jsonPointerAppend("/area_priors", i);
    const auto aoi_id = stringAt(pr, "aoi_id");
    const Polygon* aoi = nullptr;
    if (aoi_id) {
      if (!aoi_ids.has(*aoi_id)) {
        add(p + "/aoi_id", "prior_aoi", "no area of interest has id '" + *aoi_id + "'");
      } else if (!covered.insert(*aoi_id).second) {
        add(p + "/aoi_id", "prior_aoi", "a second prior for area of interest '" + *aoi_id + "'");
      }
      if (auto it = aois.find(*aoi_id); it != aois.end()) aoi = &it->second;
    }
    const json* depth = member(pr, "depth");
    const json& cells = arrayOrEmpty(pr, "cells");
    long n = -1;
    if (depth && isInteger(*depth) && depth->get<double>() >= 0 && depth->get<double>() <= 8) {
      n = 1L << depth->get<int>();
      if (static_cast<long>(cells.size()) != n * n) {
        add(p + "/cells", "prior_cells",
            "expected " + std::to_string(n * n) + " cells (" + std::to_string(n) + " x " +
                std::to_string(n) + " for depth " + depth->dump() + "), got " +
                std::to_string(cells.size()));
      }
    }
    std::set<std::pair<long, long>> places;
    double sum = 0.0;
    bool all_numbers = !cells.empty();
    for (std::size_t c = 0; c < cells.size(); ++c) {
      const json& cell = cells[c];
      const std::string cp = jsonPointerAppend(p + "/cells", c);
      cell_ids.note(cell, cp);
      const json* row = member(cell, "row");
      const json* col = member(cell, "col");
      const auto row_value = row ? integerAs<long>(*row) : std::nullopt;
      const auto col_value = col ? integerAs<long>(*col) : std::nullopt;
      if (row && col && isInteger(*row) && isInteger(*col) && !(row_value && col_value)) {
        add(cp, "prior_cells",
            "row " + row->dump() + ", col " + col->dump() + " lies outside the grid");
      } else if (row_value && col_value) {
        const long r = *row_value, k = *col_value;
        if (n > 0 && (r < 0 || r >= n || k < 0 || k >= n)) {
          add(cp, "prior_cells",
              "row " + std::to_string(r) + ", col " + std::to_string(k) + " lies outside the " +
                  std::to_string(n) + " x " + std::to_string(n) + " grid");
        } else if (!places.insert({r, k}).second) {
          add(cp, "prior_cells",
              "a second cell at row " + std::to_string(r) + ", col " + std::to_string(k));
        }
      }
      if (const json* poly = member(cell, "polygon")) {
        const auto pg = polygon(*poly, cp + "/polygon");
        if (pg && aoi) {
          for (const Vec2& v : pg->vertices()) {
            if (aoi->distance(v) > 0.01) {
              add(cp + "/polygon", "prior_cells",
                  "vertex (" + num(v.x()) + ", " + num(v.y()) +
                      ") lies outside area of interest '" + *aoi_id + "'");
              break;
            }
          }
        }
      }
      if (const auto prob = numberAt(cell, "probability"))
        sum += *prob;
      else
        all_numbers = false;
    }
    if (all_numbers && std::abs(sum - 1.0) > 1e-6) {
      add(p + "/cells", "prior_sum",
          "cell probabilities sum to " + num(sum) + ", expected 1 (within 1e-6)");
    }
  }
}

void Semantics::relations(const IdSet& targets) {
  const json& rels = arrayOrEmpty(doc_, "scene_relations");
  for (std::size_t i = 0; i < rels.size(); ++i) {
    const json& r = rels[i];
    const std::string p = jsonPointerAppend("/scene_relations", i);
    if (const auto t = stringAt(r, "target"); t && !targets.has(*t)) {
      add(p + "/target", "relation_target", "'" + *t + "' is not among the objective's target ids");
    }
    const auto op_name = stringAt(r, "operator");
    RelationOp op;
    bool eventually = false;
    if (!op_name || !parseRelationOp(*op_name, &op, &eventually)) continue;  // schema: enum
    const bool part_of = op == RelationOp::kPartOf;
    const json* related = member(r, "related");
    const auto related_cls = related ? stringAt(*related, "class") : std::nullopt;
    if (related_cls && part_of != (*related_cls == "group")) {
      add(p + "/operator", "relation_operator",
          part_of
              ? "PART_OF relates the target to a group, but the related class is '" + *related_cls +
                    "'"
              : *op_name + " relates the target to an entity, but the related class is 'group'");
    }
    const json* ev = member(r, "evidence");
    if (!ev || !ev->is_object()) continue;
    const std::string ep = p + "/evidence";
    for (const char* k : {"distance", "bearing_deg", "dz", "line_of_sight"}) {
      if (part_of && ev->contains(k)) {
        add(ep, "relation_evidence",
            "PART_OF has no geometric evidence, but '" + std::string(k) + "' is given");
      } else if (!part_of && !ev->contains(k)) {
        add(ep, "relation_evidence", *op_name + " needs '" + std::string(k) + "' in its evidence");
      }
    }
    if (eventually && !ev->contains("time")) {
      add(ep, "relation_evidence", *op_name + " needs 'time', the first time it holds");
    } else if (!eventually && ev->contains("time")) {
      add(ep, "relation_evidence",
          "'time' is only given for EVENTUALLY_* operators, not " + *op_name);
    }
  }
}

}  // namespace hameritt::scenario::validation_internal
