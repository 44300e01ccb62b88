;;;; Package CRAM-DESIGNATORS (nickname DESIG): symbolic descriptions of actions, motions,
;;;; locations, objects and humans, grounded through extendable Prolog predicates.

(defpackage :cram-designators
  (:nicknames :desig)
  (:use :cl :cram-utilities :cram-prolog)
  (:export
   ;; conditional properties inside A / AN / ALL (this is CL:WHEN, re-exported)
   #:when
   ;; hooks
   #:hooks #:on-equate-designators
   ;; classes and construction
   #:designator #:designator-p #:action-designator #:motion-designator
   #:location-designator #:object-designator #:human-designator
   #:register-designator-class #:find-designator-class #:designator-type
   #:normalize-designator-description
   #:make-designator #:a #:an #:all
   ;; description access
   #:description #:properties #:quantifier #:desig-prop-value #:desig-prop-values
   #:copy-designator #:update-designator-properties #:extend-designator-properties
   #:make-effective-designator
   ;; equation chains
   #:equate #:desig-equal #:first-desig #:current-desig #:newest-effective-designator
   #:get-equal-designators #:parent #:successor #:effective #:timestamp #:designator-data
   #:data
   ;; grounding
   #:reference #:resolve-designator #:next-solution #:reset #:designator-solutions
   #:*default-role* #:designator-error #:designator-error-designator
   #:designator-error-reason #:location-resolution-error
   ;; object designators
   #:object-designator-data #:object-identifier #:object-pose
   ;; location designators
   #:register-location-generator #:delete-location-generator-function
   #:register-location-validation-function #:register-location-validator-function
   #:delete-location-validation-function #:location-generators #:location-validators
   #:*location-generator-max-retries* #:with-designator-solution-filter
   #:next-different-location-solution #:*location-solution-distance-function*
   ;; Prolog predicates
   #:action-grounding #:motion-grounding #:location-grounding
   #:desig-prop #:desig-description #:desig-class #:desig-equal
   #:action-desig? #:motion-desig? #:loc-desig? #:obj-desig? #:human-desig?
   #:current-designator #:designator-groundings))
