#pragma once
// Combining occlusion testers. Every `occluded` answer is a proof, so a box is
// occluded when ANY tester proves it; the result is as conservative as its parts.
// Not on the server's path: the property test uses it (docs/architecture.md, "Seed and
// alternative implementations").

#include "dsoc/visibility/box_visibility.hpp"
#include "dsoc/visibility/geometry.hpp"

namespace dsoc::visibility {

/// `occluded` when `first` or `second` answers `occluded` (first is asked first: put
/// the cheaper or more often successful tester there). Both must outlive this object.
/// A and B: anything with `Visibility test_box(const Aabb&) const`.
template <class A, class B>
class EitherOccludes {
public:
    EitherOccludes(const A& first, const B& second) : first_(&first), second_(&second) {}
    [[nodiscard]] Visibility test_box(const Aabb& box) const {
        if (first_->test_box(box) == Visibility::occluded) {
            return Visibility::occluded;
        }
        return second_->test_box(box);
    }

private:
    const A* first_;
    const B* second_;
};

} // namespace dsoc::visibility
