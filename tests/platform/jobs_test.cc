#include "platform/jobs.h"

#include <gtest/gtest.h>

namespace floorpose::platform {
namespace {

constexpr int64_t kSecond = 1'000'000'000;

TEST(SearchBudgetTest, SpendsItsShareOfACoreOverTheHorizon) {
  SearchBudget budget(0.01);  // 6 s of CPU over 600 s
  ASSERT_TRUE(budget.Allows(0)) << "full at the start";
  budget.Spend(4.0, 0);
  EXPECT_TRUE(budget.Allows(0)) << "2 s left";
  budget.Spend(4.0, 0);
  EXPECT_FALSE(budget.Allows(0)) << "2 s in debt";
  EXPECT_FALSE(budget.Allows(199 * kSecond)) << "1% of 199 s does not pay 2 s";
  EXPECT_TRUE(budget.Allows(201 * kSecond));
}

TEST(SearchBudgetTest, HoldsNoMoreThanTheHorizonEarnsAndNothingAtZero) {
  SearchBudget budget(0.01);
  ASSERT_TRUE(budget.Allows(0));
  EXPECT_TRUE(budget.Allows(10'000 * kSecond));  // a long quiet stretch...
  budget.Spend(6.5, 10'000 * kSecond);           // ...saved 6 s, not 100 s
  EXPECT_FALSE(budget.Allows(10'049 * kSecond));
  EXPECT_TRUE(budget.Allows(10'051 * kSecond));
  // The headset's clock started again: its stamps earn from where they are.
  budget.Spend(1.0, 0);
  EXPECT_FALSE(budget.Allows(98 * kSecond)) << "about 1 s in debt";
  EXPECT_TRUE(budget.Allows(101 * kSecond));

  SearchBudget none(0.0);
  EXPECT_FALSE(none.Allows(0)) << "limits.search_cpu 0: no plan searches";
  EXPECT_FALSE(none.Allows(1'000'000 * kSecond));
}

TEST(SearchBudgetTest, PricesASearchByItsPointBoundsNotByAClock) {
  EXPECT_DOUBLE_EQ(SearchBudget::CpuS(0), 0.0);
  // A million nodes of 400 points: a second of CPU at 2.5 ns a point bound.
  EXPECT_DOUBLE_EQ(SearchBudget::CpuS(1e6 * 400), 1.0);
}

}  // namespace
}  // namespace floorpose::platform
