;;;; CRAM compatibility for the seed-era (2017, Cram4) API: the packages and names that code of
;;;; that era (the first Bullet world tutorial) types, mapped onto today's implementation.
;;;; Everything here is an alias or a thin adapter; the work is done by the current layers.

(defpackage :cram-plans-compat
  (:use :cl :cram-prolog)
  (:export #:modern-location-description #:known-location-keys #:register-location-key
           #:old-surface-link #:*object-name-aliases*))

;;; cram_occupancy_grid_costmap: the occupancy map for navigation.
(defpackage :cram-occupancy-grid-costmap
  (:nicknames :occupancy-grid-costmap)
  (:use :cl)
  (:export #:init-occupancy-grid-costmap #:occupancy-grid #:occupancy-grid-width
           #:occupancy-grid-height #:occupancy-grid-resolution #:occupancy-grid-origin
           #:occupied-p #:*occupancy-map-file*))

;;; cram_bullet_reasoning_belief_state: the belief state's clock.
(defpackage :cram-bullet-reasoning-belief-state
  (:nicknames :btr-belief)
  (:use :cl)
  (:export #:ros-time-init #:belief-time))

;;; cram_pr2_pick_place_plans (2017): the plans the tutorial calls, over PP-PLANS.
(defpackage :cram-pr2-pick-place-plans
  (:nicknames :pr2-pp-plans)
  (:use :cl)
  (:import-from :cram-mobile-pick-place-plans #:park-arms)
  (:export #:park-arms #:perceive #:drive-towards-object-plan #:drive-to-reach-pose
           #:drive-and-pick-up-plan #:*pr2-left-arm-out-of-sight-joint-positions*
           #:*pr2-right-arm-out-of-sight-joint-positions*
           #:*meal-table-left-base-pose* #:*meal-table-right-base-pose*
           #:*meal-table-left-base-look-pose* #:*meal-table-right-base-look-pose*
           #:*meal-table-left-base-look-down-pose*))

;;; Names the era's code reads from existing packages.
(export (intern "PR2" :cram-pr2-description) :cram-pr2-description)
(export (intern "ROBOT-ARMS-PARKING-JOINT-STATES" :cram-robot-interfaces) :cram-robot-interfaces)
(export (intern "LOCATION-COSTMAP-VIS-INIT" :cram-location-costmap) :cram-location-costmap)
(export (intern "INIT-TF" :cram-tf) :cram-tf)
