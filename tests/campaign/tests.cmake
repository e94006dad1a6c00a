# A slice of the randomized campaign (scripts/campaign runs all of it): seeds 0..19
# must all succeed (the campaign requires >= 99 %). The program is an example target,
# defined after the tests; add_test resolves the target name at generation time.
if(INHAND_HAVE_CAMPAIGN)
  add_test(NAME campaign.slice_seeds_0_19
           COMMAND inhand_campaign --first-seed 0 --count 20 --min-success 0.99)
  set_tests_properties(campaign.slice_seeds_0_19 PROPERTIES LABELS campaign TIMEOUT 300)
endif()
