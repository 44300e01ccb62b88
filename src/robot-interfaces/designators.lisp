;;;; Which location designators ask for a place to see from or to reach from.

(in-package :cram-robot-interfaces)

(def-fact-group reachability-and-visibility-designators ()
  ;; (visibility-designator ?designator): ?designator is (a location (visible-for ?robot) ...)
  (<- (visibility-designator ?designator)
    (lisp-pred typep ?designator desig:location-designator)
    (desig:desig-prop ?designator (:visible-for ?_)))
  ;; (reachability-designator ?designator): ?designator is (a location (reachable-for ?robot) ...)
  (<- (reachability-designator ?designator)
    (lisp-pred typep ?designator desig:location-designator)
    (desig:desig-prop ?designator (:reachable-for ?_))))

(defun visibility-designator-p (designator)
  "True when DESIGNATOR is a location designator with a VISIBLE-FOR property: a place from which
the robot sees something."
  (and (prolog `(visibility-designator ,designator)) t))

(defun reachability-designator-p (designator)
  "True when DESIGNATOR is a location designator with a REACHABLE-FOR property: a place from
which the robot reaches something."
  (and (prolog `(reachability-designator ,designator)) t))
