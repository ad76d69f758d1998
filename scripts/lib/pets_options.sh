# The PETS 2009 demo's track_offline options, one definition for scripts/demo, scripts/measure
# and the real-footage tests. Sourced, with $repo set to the checkout:
#   source "$repo/scripts/lib/pets_options.sh"
#   rosrun kneed_walker track_offline "${pets_woman[@]}" --num-particles 2000 --out-csv ...
#
# PETS 2009 was captured at about 7 fps (its AVI header says 10): the tracker's frame interval.
# Both runs may walk the gait table's slow walks (from 1.5 km/h and 0.3 m steps) and start from
# 1.5 km/h: people stroll and pause there. At 7 fps, with people 60-145 px tall, the optical flow
# misleads more than it helps (--use-optical-flow false). A track that drifts off its person keeps a positive
# log-likelihood ratio far below its usual one: it is lost after 3 frames below 0.4 of its median
# over the last 20 (--lost-likelihood-fraction 0.4) and started again. Measured: doc/results.md.
pets_data="$repo/../shared/data/pets2009"
pets_video="$pets_data/vtest.avi"
pets_camera="$pets_data/View_001_camera.yml"
pets_detector_boxes="$pets_data/View_001_person_boxes.csv"
pets_common=(--video "$pets_video" --camera "$pets_camera" --fps 7
  --min-gait-speed-kmh 1.5 --min-gait-step-m 0.3 --min-start-speed-kmh 1.5 --use-optical-flow false --lost-likelihood-fraction 0.4)
# The woman in black crossing the lawn (frames 600-794), from the detector's box there and her
# direction from its box five frames on; her coat is broader than the model's bare torso.
pets_woman=("${pets_common[@]}" --boxes "$pets_detector_boxes" --first-frame 600 --person-height-m 1.65 --person-breadth-scale 1.4)
pets_woman_particles=2000
# Everyone who walks, found by the tracker itself, up to 10 at once; resampling from one frame
# back (--resample-lag-frames 1) halves the time at the same accuracy.
pets_people=("${pets_common[@]}" --person-height-m 1.7 --person-breadth-scale 1.5 --max-people 10 --resample-lag-frames 1)
pets_people_particles=500
