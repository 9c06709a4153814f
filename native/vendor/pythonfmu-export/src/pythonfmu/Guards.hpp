
#ifndef PYTHONFMU_GUARDS_HPP
#define PYTHONFMU_GUARDS_HPP

// navfmu patch (the whole file): the FMI 2.0 co-simulation state machine of an instance and
// the registry of live instances and FMU states, so that a call on an unknown or freed
// pointer is refused without dereferencing it.

#include <mutex>
#include <optional>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>
#include <vector>

namespace pythonfmu
{

// The states of FMI 2.0's co-simulation state machine (section 4.2.4) an instance can be in
// between two calls (stepInProgress only during fmi2DoStep: it never returns fmi2Pending),
// one bit each so that a set of them is a mask.
enum class Phase : unsigned
{
    instantiated = 1,
    initializationMode = 2,
    stepComplete = 4,
    stepInProgress = 8,
    stepFailed = 16,
    terminated = 32,
    error = 64,
    fatal = 128
};

inline const char* phaseName(Phase p)
{
    switch (p) {
        case Phase::instantiated: return "instantiated";
        case Phase::initializationMode: return "initializationMode";
        case Phase::stepComplete: return "stepComplete";
        case Phase::stepInProgress: return "stepInProgress";
        case Phase::stepFailed: return "stepFailed";
        case Phase::terminated: return "terminated";
        case Phase::error: return "error";
        default: return "fatal";
    }
}

// The phase an FMU state's recorded name stands for (a deserialized state: see
// fmushell.fmu_state.FmuState.fmi2_phase); instantiated when the name is unknown.
inline Phase phaseNamed(const std::string& name)
{
    if (name == "stepComplete") return Phase::stepComplete;
    if (name == "error") return Phase::error;
    return Phase::instantiated;
}

// The phases in which FMI 2.0 allows each call (section 4.2.4's table for co-simulation).
namespace allowed
{
constexpr unsigned I = 1, IM = 2, SC = 4, SP = 8, SF = 16, T = 32, E = 64;
constexpr unsigned setDebugLogging = I | IM | SC | SP | SF | T | E;
constexpr unsigned setupExperiment = I;
constexpr unsigned enterInitializationMode = I;
constexpr unsigned exitInitializationMode = IM;
constexpr unsigned terminate = SC | SF;
constexpr unsigned reset = I | IM | SC | SF | T | E;
constexpr unsigned getValues = IM | SC | SF | T | E;
constexpr unsigned setValues = I | IM | SC;
constexpr unsigned fmuState = I | IM | SC | SF | T | E;
constexpr unsigned doStep = SC;
constexpr unsigned getStatus = SC | SP | SF | T;
} // namespace allowed

// "a, b or c": the phases of a mask, for a message.
inline std::string phaseNames(unsigned mask)
{
    std::vector<std::string> names;
    for (unsigned bit = 1; bit <= static_cast<unsigned>(Phase::fatal); bit <<= 1) {
        if (mask & bit) names.emplace_back(phaseName(static_cast<Phase>(bit)));
    }
    std::string text;
    for (std::size_t i = 0; i < names.size(); ++i) {
        text += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
    }
    return text;
}

// The live instances and FMU states of this library, each FMU state with the instance that
// made it and the phase it restores.  One mutex guards both; a lookup holds it only while it
// looks (FMI 2.0 forbids concurrent calls on one instance; this guards the registry itself
// against calls on different instances from different threads).
template <typename Component>
class Registry
{
public:
    void add(Component* c)
    {
        const std::lock_guard lock{mutex_};
        components_.insert(c);
    }

    // The live instance ``c`` points to, or nullptr.
    Component* find(const void* c) const
    {
        const std::lock_guard lock{mutex_};
        const auto it = components_.find(static_cast<Component*>(const_cast<void*>(c)));
        return it == components_.end() ? nullptr : *it;
    }

    // Removes ``c`` with the FMU states it made, which are returned (for their release);
    // nullopt if ``c`` was not live (a second free).
    std::optional<std::vector<void*>> remove(Component* c)
    {
        const std::lock_guard lock{mutex_};
        if (components_.erase(c) == 0) return std::nullopt;
        std::vector<void*> owned;
        for (auto it = states_.begin(); it != states_.end();) {
            if (it->second.first == c) {
                owned.push_back(it->first);
                it = states_.erase(it);
            } else {
                ++it;
            }
        }
        return owned;
    }

    void addState(void* state, Component* owner, Phase phase)
    {
        const std::lock_guard lock{mutex_};
        states_[state] = {owner, phase};
    }

    // The phase a live FMU state restores, or nullopt for an unknown or freed one.
    std::optional<Phase> statePhase(const void* state) const
    {
        const std::lock_guard lock{mutex_};
        const auto it = states_.find(const_cast<void*>(state));
        if (it == states_.end()) return std::nullopt;
        return it->second.second;
    }

    // Forgets a live FMU state; false if it was not live.
    bool removeState(void* state)
    {
        const std::lock_guard lock{mutex_};
        return states_.erase(state) > 0;
    }

private:
    mutable std::mutex mutex_;
    std::unordered_set<Component*> components_;
    std::unordered_map<void*, std::pair<Component*, Phase>> states_;
};

} // namespace pythonfmu

#endif // PYTHONFMU_GUARDS_HPP
