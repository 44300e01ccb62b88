;;;; Package CRAM-LOCATION-COSTMAP (nickname COSTMAP): location costmaps, and the metadata
;;;; predicates (map size, resolution, paddings, reach) that robot descriptions and
;;;; environments provide.

(defpackage :cram-location-costmap
  (:nicknames :costmap :location-costmap)
  (:use :cl :cram-prolog)
  (:export
   ;; metadata predicates
   #:costmap-size #:costmap-origin #:costmap-resolution
   #:costmap-padding #:costmap-manipulation-padding
   #:costmap-in-reach-distance #:costmap-reach-minimal-distance
   #:visibility-costmap-size #:orientation-samples #:orientation-sample-step
   #:robot-costmap-metadata #:current-robot-costmap-metadata
   ;; costmaps
   #:location-costmap #:make-location-costmap #:get-cost-map #:get-map-value
   #:costmap-samples #:register-cost-function #:register-height-generator
   #:register-orientation-generator #:costmap-generator-name->score
   #:desig-costmap #:merge-costmaps
   ;; cost functions and generators
   #:make-gauss-cost-function #:make-range-cost-function
   #:make-occupancy-grid-cost-function #:make-padding-mask
   #:make-constant-height-function #:make-matrix-cost-function
   #:make-axis-boundary-cost-function #:make-angle-to-point-generator
   #:make-orientation-generator #:make-identity-orientation-generator
   ;; occupancy grids
   #:occupancy-grid #:make-occupancy-grid
   #:invalid-probability-distribution))
