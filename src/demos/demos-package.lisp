;;;; Package CRAM-PROJECTION-DEMOS (DEMOS): CRAM's household demo in projection — a PR2 sets a
;;;; breakfast table from closed drawers, the fridge door and the oven drawer, then cleans it.

(defpackage :cram-projection-demos
  (:nicknames :demos)
  (:use :cl)
  (:export #:household-demo #:initialize #:spawn-objects-on-fixed-spots #:park-robot
           #:*object-spawning-poses* #:*household-joints* #:*demo-object-types*
           #:demo-object-name))

(in-package :cram-projection-demos)

(defparameter *demo-object-types* '(:bowl :breakfast-cereal :milk :cup :spoon)
  "The objects of the household demo, in the order the table is set.")

(defparameter *household-joints*
  '("sink_area_left_upper_drawer_main_joint" "sink_area_left_middle_drawer_main_joint"
    "sink_area_left_bottom_drawer_main_joint" "iai_fridge_door_joint"
    "sink_area_dish_washer_door_joint" "sink_area_dish_washer_tray_main"
    "oven_area_area_right_drawer_main_joint" "sink_area_trash_drawer_main_joint"
    "kitchen_island_left_upper_drawer_main_joint")
  "The kitchen joints the demo closes (sets to 0) when it starts.")

(defparameter *object-spawning-poses*
  '((:bowl "sink_area_left_middle_drawer_main" ((0.10 -0.0505 -0.062256) (0 0 -1 0)))
    (:cup "kitchen_island_left_upper_drawer_main" ((0.11 0.08 -0.026367) (0 0 -1 0)))
    (:spoon "sink_area_left_upper_drawer_main"
     ((0.125 0 -0.0136) (0 -0.053938 -0.998538 -0.003418)))
    (:breakfast-cereal "oven_area_area_right_drawer_board_3_link"
     ((0.10 -0.03 0.11) (0.0087786 0.005395 -0.838767 -0.544393)))
    (:milk "iai_fridge_door_shelf1_bottom" ((-0.01 -0.05 0.094) (0 0 0 1))))
  "(type link ((x y z) (qx qy qz qw))): where each demo object is spawned, in its container
link's frame.")

(defun demo-object-name (type)
  "The belief-state name of the demo object of TYPE, e.g. :BOWL-1."
  (intern (format nil "~a-1" (symbol-name type)) :keyword))
