// A non-owning reference to a callable, for callbacks that run only during the call they are passed to
// (the surface visitors of visibility walks). std::function would copy a capturing lambda to the heap once
// per call whenever its captures exceed the small-buffer size, i.e. once per path vertex in the path
// tracer's emitter search (issue 17: no heap allocation per path or vertex); this costs one indirect call.
#pragma once
#include <type_traits>
#include <utility>

namespace pf {

template <class Signature>
class FunctionRef;

template <class R, class... Args>
class FunctionRef<R(Args...)> {
public:
    // The callable must outlive every call through this reference (a lambda passed to a function argument
    // lives until the end of the full expression).
    template <class F, class = std::enable_if_t<!std::is_same_v<std::decay_t<F>, FunctionRef> &&
                                                std::is_invocable_r_v<R, F &, Args...>>>
    FunctionRef(F &&f)  // NOLINT(google-explicit-constructor): binds like std::function does
        : object_(const_cast<void *>(static_cast<const void *>(&f))), call_([](void *object, Args... args) -> R {
              return (*static_cast<std::remove_reference_t<F> *>(object))(std::forward<Args>(args)...);
          }) {}

    R operator()(Args... args) const { return call_(object_, std::forward<Args>(args)...); }

private:
    void *object_;
    R (*call_)(void *, Args...);
};

}  // namespace pf
