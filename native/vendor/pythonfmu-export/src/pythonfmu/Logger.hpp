
#ifndef PYTHONFMU_LOGGER_HPP
#define PYTHONFMU_LOGGER_HPP

#include "fmi/fmi2Functions.h"

#include <algorithm>
#include <string>
#include <vector>

namespace pythonfmu
{

class PyLogger
{

public:
    explicit PyLogger(std::string instanceName)
        : instanceName_(std::move(instanceName))
    { }

    void setDebugLogging(bool flag, const std::vector<std::string>& categories = {})
    {
        debugLogging_ = flag;
        categories_ = categories;
    }

    // Logs a message.
    void log(fmi2Status s, const std::string& message)
    {
        log(s, "", message);
    }

    // navfmu patch: every message reaches the host with a category (one of the model
    // description's LogCategories: the status's when none is given), never NULL; messages of
    // status Warning, Discard, Error and Fatal are reported whatever loggingOn and
    // fmi2SetDebugLogging say (those switch the debug messages, status OK or Pending, and
    // choose their categories), and an instance passes at most kMaxDebugMessages debug
    // messages.
    void log(fmi2Status s, const std::string& category, const std::string& message)
    {
        const std::string& cat = category.empty() ? statusCategory(s) : category;
        if (s >= fmi2Warning && s <= fmi2Fatal) {
            debugLog(s, cat, message);
            return;
        }
        if (!debugLogging_ || debugMessages_ >= kMaxDebugMessages) return;
        if (!categories_.empty() &&
            std::find(categories_.begin(), categories_.end(), cat) == categories_.end()) {
            return;
        }
        if (++debugMessages_ == kMaxDebugMessages) {
            debugLog(s, cat, message + " (debug message limit of this instance reached: "
                                       "no further debug messages)");
        } else {
            debugLog(s, cat, message);
        }
    }

    // navfmu patch: the category of a message logged without one
    static const std::string& statusCategory(fmi2Status s)
    {
        static const std::string warning{"logStatusWarning"}, discard{"logStatusDiscard"},
            error{"logStatusError"}, fatal{"logStatusFatal"}, events{"logEvents"};
        switch (s) {
            case fmi2Warning: return warning;
            case fmi2Discard: return discard;
            case fmi2Error: return error;
            case fmi2Fatal: return fatal;
            default: return events;
        }
    }

    static constexpr unsigned long kMaxDebugMessages = 10000;

    virtual ~PyLogger() = default;

private:
    bool debugLogging_{false};
    unsigned long debugMessages_{0}; // navfmu patch

protected:
    std::string instanceName_;
    std::vector<std::string> categories_;

    virtual void debugLog(fmi2Status s, const std::string& category, const std::string& message) = 0;
};

} // namespace pythonfmu

#endif // PYTHONFMU_LOGGER_HPP
