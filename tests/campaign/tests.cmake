# A slice of the randomized campaign (scripts/campaign runs all of it): seeds 0..19
# must all succeed (the campaign requires >= 99 %). The program is an example target,
# defined after the tests; add_test resolves the target name at generation time.
if(INHAND_HAVE_CAMPAIGN)
  add_test(NAME campaign.slice_seeds_0_19
           COMMAND inhand_campaign --first-seed 0 --count 20 --min-success 0.99)
  # The wide ranges' first 200 seeds at their measured rate less a margin: 200 of 200 pass
  # (seed 7, a 349 g cylinder squeezed out along gravity, failed before the grasp aimed at
  # gravity's side); at most 4 may fail.
  add_test(NAME campaign.wide_slice_seeds_0_199
           COMMAND inhand_campaign --wide --first-seed 0 --count 200 --min-success 0.98)
  # The two slices are rates over many draws of the same code, so they also carry the label
  # long, which the sanitizer stage of scripts/test leaves out: the 200 wide seeds take about
  # 35 s uninstrumented and more than 300 s under ASan and UBSan, while every path they take
  # (grasp, release, task, the plant) is run instrumented by the single seeds below and the
  # scenario files.
  set_tests_properties(campaign.slice_seeds_0_19 campaign.wide_slice_seeds_0_199
                       PROPERTIES LABELS "campaign;long" TIMEOUT 300)
  # A heavy cylinder that slides out at release (wide seeds 261: 356 g at friction 0.47 on
  # the three-finger hand, and 2715: 394 g at 0.41 on the Shadow-like one, gravity across the
  # fingers' normals, pads under 1 kN/m): beyond the hand at max_force, so the case fails,
  # but beyond_capacity must be the first warning raised before its first contact opens (89
  # and 74 ms before, measured). (Seeds 2000 and 2115, here before, are now held.)
  foreach(seed 261 2715)
    add_test(NAME campaign.wide_slide_at_release_is_warned_${seed}
             COMMAND inhand_campaign --wide --first-seed ${seed} --count 1 --min-success 0)
    set_tests_properties(campaign.wide_slide_at_release_is_warned_${seed} PROPERTIES
                         LABELS campaign TIMEOUT 120
                         PASS_REGULAR_EXPRESSION "FAIL.*; beyond_capacity [0-9]+ ms before the first contact opened")
  endforeach()
  # The regression cases below were found with the wide draw whose tangential stiffness
  # stayed at the plant default (2 kN/m) whatever the normal one; --fixed-shear-stiffness
  # replays them as they were found.
  # Wide-range cases whose grasp timed out before a pressing finger's contact normal had
  # priority in the IK at its joint limits (the thumb of seed 301 pressed 6.3 N against a
  # 0.6 N target, seed 988's did not settle; both spheres with +0.1 N of force bias).
  add_test(NAME campaign.wide_grasp_at_a_joint_limit
           COMMAND inhand_campaign --wide --fixed-shear-stiffness --first-seed 301 --count 1 --min-success 1)
  add_test(NAME campaign.wide_grasp_at_a_joint_limit_988
           COMMAND inhand_campaign --wide --fixed-shear-stiffness --first-seed 988 --count 1 --min-success 1)
  set_tests_properties(campaign.wide_grasp_at_a_joint_limit campaign.wide_grasp_at_a_joint_limit_988
                       PROPERTIES LABELS campaign TIMEOUT 120)
  # Wide-range cases whose grasp timed out in a force cycle: two fingers of each (behind
  # 6.7 ms of actuator lag in 743, 9.6 ms in 382) lost their contacts 14-15 times between
  # 1.5 s and 3 s, each time coming back at approach speed and hitting the sphere with up
  # to 2.3 N (controller/grasp.hpp: a finger that has touched now comes back at creep speed).
  foreach(seed 382 743)
    add_test(NAME campaign.wide_grasp_force_cycle_${seed}
             COMMAND inhand_campaign --wide --fixed-shear-stiffness --first-seed ${seed} --count 1 --min-success 1)
    set_tests_properties(campaign.wide_grasp_force_cycle_${seed} PROPERTIES LABELS campaign TIMEOUT 120)
  endforeach()
  # Wide-range cases whose thumb reaches a joint limit during the task: the other fingers
  # carried the object on and the grasp deformed until a contact opened (481: dropped;
  # 550: dropped). With the twist kept within reach the object stops at the limit and
  # comes back with the reciprocating task, within the campaign's bounds.
  foreach(seed 481 550)
    add_test(NAME campaign.wide_thumb_at_a_limit_kept_in_reach_${seed}
             COMMAND inhand_campaign --wide --fixed-shear-stiffness --first-seed ${seed} --count 1 --min-success 1
                     --keep-twist-in-reach)
    set_tests_properties(campaign.wide_thumb_at_a_limit_kept_in_reach_${seed}
                         PROPERTIES LABELS campaign TIMEOUT 120)
  endforeach()
  # The same edge without the option: the twist is kept within reach on the ticks where
  # the force layer reports the grasp at risk (beyond_capacity or slipping;
  # controller_phases.hpp). Default-range seed 1620 (a 100 g sphere; the thumb at its
  # limit from 3.2 s, slipping and beyond capacity from 3.7 s) was dropped at 4.23 s;
  # wide seed 550 was dropped too. Both now end within the campaign's bounds.
  add_test(NAME campaign.thumb_at_a_limit_grasp_at_risk_1620
           COMMAND inhand_campaign --first-seed 1620 --count 1 --min-success 1)
  add_test(NAME campaign.wide_thumb_at_a_limit_grasp_at_risk_550
           COMMAND inhand_campaign --wide --fixed-shear-stiffness --first-seed 550 --count 1 --min-success 1)
  set_tests_properties(campaign.thumb_at_a_limit_grasp_at_risk_1620
                       campaign.wide_thumb_at_a_limit_grasp_at_risk_550
                       PROPERTIES LABELS campaign TIMEOUT 120)
  # Wide-range cases whose held thumb was pressed at its limit (481: 4.2 -> 6.5 N against
  # 4 N, the opposite finger's contact opening 14 times in a cycle of about 104 ms, the cut
  # released whenever the grasp stopped reporting a risk; 498: every contact kept, final
  # error 0.516 mm against 0.5 mm). The cut now stays on while the twist asks beyond the
  # edge, and the pose loop does not wind up along it (workspace_limits.hpp): both pass.
  # Wide spheres that the task pushed into a thumb held at its limit (1449: 201 g, 1627:
  # 340 g): the thumb was pressed from 4 N to 7.4 N (max_force 6 N) while another finger
  # unloaded, and the at-risk cut came only with that finger's slip 150 ms later, when its
  # contact was already opening: both dropped. A touching finger pressed beyond max_force
  # (force_layer_params.hpp, over_max_force) now counts as the grasp at risk: the twist is
  # cut at the edge at once and both end within the bounds.
  foreach(seed 481 498 1449 1627)
    add_test(NAME campaign.wide_thumb_pressed_at_a_limit_${seed}
             COMMAND inhand_campaign --wide --first-seed ${seed} --count 1 --min-success 1)
    set_tests_properties(campaign.wide_thumb_pressed_at_a_limit_${seed}
                         PROPERTIES LABELS campaign TIMEOUT 120)
  endforeach()
  # Wide spheres whose task turns or pushes them past a thumb held at its limit on stiff,
  # high-friction pads (1603: 321 g, 4099: 296 g, 5217: 89 g; 4558: 139 g, 4609: 183 g): the
  # cut took out only the motion the held contact could not make along its normal, the
  # contact stuck instead of sliding across it, the sphere pivoted on the thumb and another
  # finger unloaded (1603, 4558, 4609, 5217 dropped; 4099 missed the RMS bound). Once the
  # twist is cut, the held contact's whole unreachable direction is now taken out
  # (workspace_limits.hpp): the first three pass; 4558 and 4609 keep every contact, stopped
  # at the edge (they may miss the RMS bound, not drop). Their tasks are beyond the hand's
  # reach: the campaign's kinematic check (campaign_reach.hpp) finds the thumb's path 1.10
  # and 2.58 mm outside its joints' limits, which a failing line must say.
  foreach(seed 1603 4099 5217)
    add_test(NAME campaign.wide_held_contact_sticks_${seed}
             COMMAND inhand_campaign --wide --first-seed ${seed} --count 1 --min-success 1)
    set_tests_properties(campaign.wide_held_contact_sticks_${seed}
                         PROPERTIES LABELS campaign TIMEOUT 120)
  endforeach()
  foreach(seed 4558 4609)
    add_test(NAME campaign.wide_held_contact_sticks_kept_${seed}
             COMMAND inhand_campaign --wide --first-seed ${seed} --count 1 --min-success 0 --verbose)
    set_tests_properties(campaign.wide_held_contact_sticks_kept_${seed} PROPERTIES
                         LABELS campaign TIMEOUT 120
                         PASS_REGULAR_EXPRESSION "seed +${seed} (ok |FAIL.*rms position error.+no contact opened. beyond reach: thumb [0-9.]+ mm short)")
  endforeach()
  # Wide-range cases that lost a contact a few milliseconds after release: heavy spheres on
  # the three-finger hand (114: 395 g, 634: 343 g, 792: 367 g), whose released weight took
  # a finger's whole grip at release_grip 2. The grasp now presses with a grip sized so
  # that release_load (4 N) along any direction leaves every finger min_force
  # (controller/release_grip.hpp); with --release-load 0 each fails again.
  foreach(seed 114 634 792)
    add_test(NAME campaign.wide_release_grip_sized_for_the_load_${seed}
             COMMAND inhand_campaign --wide --fixed-shear-stiffness --first-seed ${seed} --count 1 --min-success 1)
    set_tests_properties(campaign.wide_release_grip_sized_for_the_load_${seed}
                         PROPERTIES LABELS campaign TIMEOUT 120)
  endforeach()
  # Wide-range cases whose heavy object, released, fell onto one side of the squeeze (865: a
  # 376 g box, gravity -Y along the thumb-fingers axis, 19 kN/m, 8.9 ms of lag; 1482: a 394 g
  # cylinder, -Y, 48 kN/m; 3952 found in seeds 3000-3999): the fingers above it unloaded
  # faster than their loops could follow and their contacts opened for a few ticks. Told
  # which way gravity pulls, the grasp presses those fingers for the step's peak, twice the
  # weight's static share for a weight of release_load (release_grip.hpp): each is kept. The
  # same seeds with --gravity-unknown (the sizing along any direction alone) must still fail,
  # so the pair shows the sizing along gravity is what keeps them.
  foreach(seed 865 1482 3952)
    add_test(NAME campaign.wide_release_grip_sized_along_gravity_${seed}
             COMMAND inhand_campaign --wide --first-seed ${seed} --count 1 --min-success 1)
    add_test(NAME campaign.wide_release_grip_gravity_unknown_${seed}
             COMMAND inhand_campaign --wide --gravity-unknown --first-seed ${seed} --count 1 --min-success 0)
    set_tests_properties(campaign.wide_release_grip_sized_along_gravity_${seed}
                         PROPERTIES LABELS campaign TIMEOUT 120)
    set_tests_properties(campaign.wide_release_grip_gravity_unknown_${seed} PROPERTIES
                         LABELS campaign TIMEOUT 120 PASS_REGULAR_EXPRESSION "seed +${seed} FAIL")
  endforeach()
  # Wide-range heavy cylinders with gravity across the grasp, carried by friction (7: 349 g on
  # the three-finger hand, friction 0.43, gravity +Z; 813 and 2000 of the same kind): the
  # fingers, approaching from below, stopped at the alignment tolerance's edge on the side
  # away from gravity, and the squeeze pushed the object out the way gravity pulls. Aiming
  # at gravity's side (grasp.hpp, GraspParams::gravity_tilt) keeps each; with the tilt off
  # (--gravity-tilt 0) each must still fail, so the pair shows the tilt is what keeps them.
  foreach(seed 7 813 2000)
    add_test(NAME campaign.wide_grasp_on_gravitys_side_${seed}
             COMMAND inhand_campaign --wide --first-seed ${seed} --count 1 --min-success 1)
    add_test(NAME campaign.wide_grasp_without_gravity_tilt_${seed}
             COMMAND inhand_campaign --wide --gravity-tilt 0 --first-seed ${seed} --count 1
                     --min-success 0)
    set_tests_properties(campaign.wide_grasp_on_gravitys_side_${seed}
                         PROPERTIES LABELS campaign TIMEOUT 120)
    set_tests_properties(campaign.wide_grasp_without_gravity_tilt_${seed} PROPERTIES
                         LABELS campaign TIMEOUT 120 PASS_REGULAR_EXPRESSION "seed +${seed} FAIL")
  endforeach()
endif()
