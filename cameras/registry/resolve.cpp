#include "cameras/registry/resolve.h"

#include <algorithm>
#include <sstream>

#include "cameras/registry/registry.h"
#include "core/util/error.h"
#include "core/util/spelling.h"

namespace aperture {

namespace {

std::string flagOf(const std::string& name) {
  const ParamSpec* s = findCameraParamSpec(name);
  return s ? s->flag() : "--" + name;
}

/// ParamSet::label for a parameter known by name.
std::string labelOf(const ParamSet& given, const std::string& name) {
  const ParamSet::Entry* e = given.find(name);
  return e ? e->source : flagOf(name);
}

/// The names of the models that read parameter `name`, in registration order.
std::vector<std::string> modelsReading(const std::string& name) {
  std::vector<std::string> users;
  for (const CameraModel* m : cameraModels())
    if (m->accepts(name)) users.emplace_back(m->name);
  return users;
}

/// The model a given parameter selects (ParamSpec::selectsModel) when no type is given.
const char* modelSelectedBy(const ParamSet& given) {
  for (const ParamSet::Entry& e : given.entries())
    if (e.spec->selectsModel) return e.spec->selectsModel;
  return nullptr;
}

void checkApplies(const ParamSet& given, const CameraModel& model) {
  for (const ParamSet::Entry& e : given.entries()) {
    if (model.accepts(e.spec->name)) continue;
    throw Error(cat(e.source, ": does not apply to a '", model.name,
                    "' camera (it applies to: ", join(modelsReading(e.spec->name), ", "), ")"));
  }
}

void checkConflictsAndCompanions(const ParamSet& given) {
  for (const ParamSet::Entry& e : given.entries()) {
    for (const char* other : e.spec->conflicts) {
      const ParamSet::Entry* o = given.find(other);
      if (!o) continue;
      std::string group = e.spec->name;
      for (const char* c : e.spec->conflicts) group += cat(", ", c);
      throw Error(cat(e.source, " and ", o->source, " conflict: give at most one of ", group));
    }
    for (const char* needed : e.spec->needs)
      if (!given.has(needed))
        throw Error(cat(e.source, " needs ", labelOf(given, needed), " as well"));
  }
}

}  // namespace

ParamSet paramSetOf(const CameraParams& p, const std::string& source) {
  const CameraParams defaults;
  ParamSet set;
  for (const ParamSpec* s : findCameraModel(p.type).params) {
    const std::optional<ParamValue> v = s->access.get(p);
    if (v && v != s->access.get(defaults)) set.set(*s, *v, source);
  }
  return set;
}

const std::vector<const ParamSpec*>& allCameraParamSpecs() {
  static const std::vector<const ParamSpec*> all = [] {
    std::vector<const ParamSpec*> v;
    for (const CameraModel* m : cameraModels())
      for (const ParamSpec* s : m->params)
        if (std::find(v.begin(), v.end(), s) == v.end()) v.push_back(s);
    return v;
  }();
  return all;
}

const ParamSpec* findCameraParamSpec(const std::string& name) {
  for (const ParamSpec* s : allCameraParamSpecs())
    if (name == s->name) return s;
  return nullptr;
}

CameraParams resolveCameraParams(const ParamSet& given, CameraParams base) {
  if (const ParamSet::Entry* t = given.find("type")) {
    const std::string& type = std::get<std::string>(t->value);
    try {
      findCameraModel(type);
    } catch (const Error& e) {
      throw Error(cat(t->source, ": ", e.what()));
    }
  }
  CameraParams p = std::move(base);
  if (const ParamSet::Entry* t = given.find("type"))
    p.type = std::get<std::string>(t->value);
  else if (const char* selected = modelSelectedBy(given))
    p.type = selected;
  checkApplies(given, findCameraModel(p.type));
  for (const ParamSet::Entry& e : given.entries()) checkParamValue(*e.spec, e.value, e.source);
  checkConflictsAndCompanions(given);
  for (const ParamSet::Entry& e : given.entries()) e.spec->access.set(p, e.value);
  return p;
}

void checkCameraParamRanges(const CameraParams& p, const ParamSet* labels) {
  for (const ParamSpec* s : findCameraModel(p.type).params) {
    const std::optional<ParamValue> v = s->access.get(p);
    if (v) checkParamValue(*s, *v, labels ? labels->label(*s) : s->flag());
  }
}

std::string describeCameraParam(const ParamSpec& spec, const CameraParams& defaults) {
  std::string s = spec.help;
  std::string facts;
  auto add = [&](const std::string& f) { facts += (facts.empty() ? "" : "; ") + f; };
  if (*spec.unit) add(spec.unit);
  if (spec.kind == ParamKind::Choice) {
    // No fixed list: the registered camera models (the `type` parameter).
    const std::vector<const char*> list = spec.choiceList();
    std::vector<std::string> words(list.begin(), list.end());
    if (words.empty()) words = cameraTypeNames();
    add(join(words, "|"));
  }
  if (!spec.range.text().empty()) add("range " + spec.range.text());
  if (spec.kind != ParamKind::Flag) add("default " + spec.defaultText(defaults));
  if (!spec.conflicts.empty()) {
    add("not with " + join(spec.conflicts, ", ", [](const char* c) { return flagOf(c); }));
  }
  for (const char* r : spec.needs) add("needs " + flagOf(r));
  return facts.empty() ? s : s + " (" + facts + ")";
}

std::string cameraParamsMarkdown() {
  std::ostringstream s;
  s << "| parameter (job key, Python) | flag | cameras | unit | default | range | conflicts / "
       "needs | meaning |\n|---|---|---|---|---|---|---|---|\n";
  for (const ParamSpec* p : allCameraParamSpecs()) {
    const std::vector<std::string> readers = modelsReading(p->name);
    const std::string users = readers.size() == cameraModels().size() ? "all" : join(readers, ", ");
    std::string rel;
    for (const char* c : p->conflicts) rel += std::string(rel.empty() ? "not " : ", not ") + c;
    for (const char* r : p->needs) rel += std::string(rel.empty() ? "needs " : ", needs ") + r;
    std::string range = p->range.text();
    for (const char* c : p->choiceList()) range += std::string(range.empty() ? "" : " \\| ") + c;
    s << "| `" << p->name << "` | `" << p->flag() << "` | " << users << " | " << p->unit << " | "
      << (p->kind == ParamKind::Flag ? "off" : p->defaultText()) << " | " << range << " | " << rel
      << " | " << p->help << " |\n";
  }
  return s.str();
}

}  // namespace aperture
