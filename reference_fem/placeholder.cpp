// Replaced by the deal.II solver sources as they land.
namespace reference_fem { void placeholder() {} }
