#include "experiment/task_kinds.h"

#include <algorithm>
#include <chrono>
#include <map>
#include <stdexcept>

#include "engine/checkpoint.h"
#include "engine/method_catalog.h"
#include "experiment/task_config.h"
#include "kernels/gemm_bf16.h"
#include "probes/cpu_class.h"

namespace sirl {

namespace {
std::vector<const TaskKindSpec*>& registry() {
  static std::vector<const TaskKindSpec*> kinds;
  return kinds;
}

const TaskKindSpec* find_kind(const std::string& name) {
  for (const TaskKindSpec* k : registry())
    if (name == k->name) return k;
  return nullptr;
}
}  // namespace

TaskKindRegistration::TaskKindRegistration(const TaskKindSpec& k) {
  const std::string name = k.name ? k.name : "";
  if (name.empty() || !k.key || !k.inputs || !k.settings || !k.cost || !k.rate || !k.shard_group ||
      !k.bf16_products || !k.describe || !k.run || !k.lacks_fields != !k.complete_fields)
    throw std::logic_error("task kind \"" + name + "\": a function of its declaration is missing");
  if (find_kind(name)) throw std::logic_error("task kind \"" + name + "\" is declared twice");
  auto& kinds = registry();
  kinds.insert(
      std::upper_bound(kinds.begin(), kinds.end(), name,
                       [](const std::string& n, const TaskKindSpec* x) { return n < x->name; }),
      &k);
}

const std::vector<const TaskKindSpec*>& task_kinds() {
  return registry();
}

const TaskKindSpec& TaskKind::spec() const {
  if (!spec_) throw std::logic_error("a task without a kind");
  return *spec_;
}

const char* TaskKind::name() const {
  return spec().name;
}

const std::string& Task::input(TaskKind k) const {
  const auto it = input_keys.find(k.name());
  if (it == input_keys.end())
    throw std::out_of_range("task " + key + " reads no " + k.name() + " task");
  return it->second;
}

const TaskConfig& Task::compiled() const {
  if (!config)
    throw std::logic_error("task " + key +
                           " has no compiled configuration (not planned by add_task)");
  return *config;
}

const Hyper& Task::hyper_values() const {
  const TaskConfig& c = compiled();
  if (!c.hyper)
    throw std::logic_error("task " + key + " (" + kind.name() + ") reads no hyper-parameters");
  return *c.hyper;
}

int Plan::count(TaskKind k) const {
  int n = 0;
  for (const auto& t : tasks) n += t.kind == k;
  return n;
}

double Plan::flops(TaskKind k) const {
  double f = 0;
  for (const auto& t : tasks)
    if (t.kind == k) f += t.flops;
  return f;
}

double Plan::protocol_flops(TaskKind k) const {
  double f = 0;
  for (const auto& t : tasks)
    if (t.kind == k) f += t.protocol_flops;
  return f;
}

bool env_precision_is_bf16(const Task& t, const Profile& p) {
  (void)p;
  return t.hyper_values().precision == "bf16";
}

bool never_bf16(const Task&, const Profile&) {
  return false;
}

void compile_env_point(const Task& t, const Profile& p, TaskConfig& c) {
  c.hyper = hyper_at(p, t.env, t.hyper);
}

namespace {
// The task's configuration: its kind's section, then what every kind has (add_task).
std::shared_ptr<const TaskConfig> compile_task(const Task& t, const Profile& p) {
  const TaskKindSpec& kind = t.kind.spec();
  Task x = t;  // the kind's settings and bf16 choice read the hyper-parameters compiled first
  auto c = std::make_shared<TaskConfig>();
  if (kind.compile) kind.compile(t, p, *c);
  if (!t.teacher.empty())
    for (const TeacherPoint& tp : p.robustness.teachers)
      if (tp.tag == t.teacher) c->teacher = tp;
  x.config = c;
  c->settings = kind.settings(x, p);
  c->bf16_products = kind.bf16_products(x, p);
  return c;
}
}  // namespace

void describe_env_and_seed(const Task& t, TaskRecord& r) {
  r.text["env"] = t.env;
  r.num["seed"] = double(t.seed);
  if (!t.hyper.empty()) r.text["hyper_point"] = t.hyper;  // base-point records stay as they were
}

int add_task(Plan& plan, const Profile& p, Task t) {
  const TaskKindSpec& kind = t.kind.spec();
  t.deps.clear();
  t.input_keys.clear();
  t.input_keys_in_order.clear();
  bool input_at_point = false;
  for (Task& in : kind.inputs(t, p)) {
    const int d = add_task(plan, p, std::move(in));
    const Task& dep = plan.tasks[size_t(d)];
    t.deps.push_back(d);
    t.input_keys[dep.kind.name()] = dep.key;
    t.input_keys_in_order.push_back(dep.key);
    input_at_point = input_at_point || !dep.hyper.empty();
  }
  t.config = compile_task(t, p);
  // A hyper-parameter point it does not read (and no input of it read) is the base task.
  if (!t.hyper.empty() && !input_at_point) {
    Task base = t;
    base.hyper.clear();
    base.config = compile_task(base, p);
    if (t.config->settings == base.config->settings) t = std::move(base);
  }
  t.key = kind.key(t);
  if (!t.hyper.empty()) {  // after "<env>/s<seed>/"
    const size_t at = t.key.find('/', t.key.find('/') + 1);
    t.key.insert(at + 1, t.hyper + "/");
  }
  if (auto it = plan.index.find(t.key); it != plan.index.end()) return it->second;
  // Refused as the plan grows, so a profile that expands to millions of tasks (a few axes'
  // product, or a stored profile text from someone else's file) costs at most the cap's memory.
  if (plan.tasks.size() >= kMaxPlanTasks)
    throw std::invalid_argument("profile " + p.name + " expands to more than " +
                                std::to_string(kMaxPlanTasks) +
                                " tasks (the paper's whole protocol is about 6,200): split it "
                                "into profiles with fewer hyper-parameter points, seeds or sizes");
  kind.cost(t, p);
  if (t.protocol_flops < t.flops) t.protocol_flops = t.flops;  // no early end expected
  const int i = int(plan.tasks.size());
  plan.index[t.key] = i;
  plan.tasks.push_back(std::move(t));
  return i;
}

bool runs_bf16_products(const Task& t) {
  return t.compiled().bf16_products;
}

std::string task_cpu_class(const Task& t) {
  // bf16 products run natively or emulated: different bits, so a different class.
  return cpu_class() + (runs_bf16_products(t) ? std::string(", bf16 ") + bf16_backend() : "");
}

TaskRecord run_task(const Task& t, RunContext& ctx) {
  const auto start = std::chrono::steady_clock::now();
  TaskRecord r;
  r.key = t.key;
  const TaskKindSpec& kind = t.kind.spec();
  r.kind = kind.name;
  kind.describe(t, r);
  try {
    kind.run(t, ctx, r);
  } catch (const StopRequested&) {
    throw;  // not a failure of the task: the run stops (engine/checkpoint.h)
  } catch (const std::exception& e) {
    throw std::runtime_error("task " + t.key + ": " + e.what());
  }
  r.num["seconds"] =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  r.num["threads"] = t.threads;  // like seconds, a fact of this run's scheduling, not a result
  // Whether its networks' products ran in bf16 (/tables/timings holds it to the bf16 roof).
  if (runs_bf16_products(t)) r.num["bf16_products"] = 1;
  r.text["cpu_class"] = task_cpu_class(t);  // what computed these bits
  // What it streams from main memory (the cost model's estimate, deterministic): with the
  // bandwidth the run measures, its memory roof in /tables/timings.
  if (t.stream_bytes > 0) r.num["stream_bytes"] = t.stream_bytes;
  return r;
}

namespace {

// /methods: the presentation of every variant the records hold (engine/method_catalog.h), so the
// figure scripts need no list of methods. Externals take their colours in the order of their
// names.
std::vector<MethodAttributes> method_attributes(const std::vector<TaskRecord>& records) {
  std::map<std::string, const TaskRecord*> variants;
  for (const TaskRecord& r : records)
    if (const auto v = r.text.find("variant"); v != r.text.end() && r.text.count("method"))
      variants.emplace(v->second, &r);
  std::vector<MethodAttributes> out;
  int externals = 0;
  for (const auto& [name, r] : variants) {
    const auto sel = r->text.find("selection");
    const auto vae = r->num.find("vae");
    VariantStyle s;
    try {
      const Method m = parse_method(r->text.at("method"));
      s = variant_style(m, vae != r->num.end() && vae->second != 0,
                        sel == r->text.end() || sel->second.empty() ? Selection::uniform
                                                                    : parse_selection(sel->second),
                        name, m == Method::external ? externals++ : 0);
    } catch (const std::invalid_argument&) {
      continue;  // a record of an engine that knew other methods: drawn with default styles
    }
    MethodAttributes a;
    a.name = name;
    a.text = {{"method", s.method},
              {"label", s.label},
              {"colour", s.colour},
              {"role", s.role},
              {"queries", s.queries},
              {"selection", s.selection},
              {"selection_label", s.selection_label},
              {"selection_colour", s.selection_colour},
              {"dashes", s.dashes}};
    a.integers = {{"figure_order", s.figure_order},        {"catalog_order", s.catalog_order},
                  {"selection_order", s.selection_order},  {"vae", int64_t(s.vae)},
                  {"best_frozen", int64_t(s.best_frozen)}, {"accepts_vae", int64_t(s.accepts_vae)}};
    out.push_back(std::move(a));
  }
  return out;
}

ResultTables tables_of(const std::vector<TaskRecord>& records, const Roofs& roofs) {
  std::vector<CellTableSpec> cells;
  for (const TaskKindSpec* k : task_kinds())
    if (!k->table.name.empty()) cells.push_back(k->table);
  // Records of an older engine (a merge or export of its files) lack fields the tables now
  // carry: complete a copy of them (only then, so a large current file is not copied).
  auto outdated = [](const TaskRecord& r) {
    const TaskKindSpec* k = find_kind(r.kind);
    return k && k->lacks_fields && k->lacks_fields(r);
  };
  if (std::any_of(records.begin(), records.end(), outdated)) {
    std::vector<TaskRecord> completed = records;
    for (TaskRecord& c : completed)
      if (outdated(c)) find_kind(c.kind)->complete_fields(c);
    return build_tables(completed, cells, roofs);
  }
  return build_tables(records, cells, roofs);
}

}  // namespace

ResultTables result_tables(const std::vector<TaskRecord>& records, const Roofs& roofs) {
  ResultTables t = tables_of(records, roofs);
  t.methods = method_attributes(records);
  return t;
}

}  // namespace sirl
