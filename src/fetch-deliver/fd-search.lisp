;;;; Searching: drive to where the search location can be seen, turn towards it and perceive
;;;; the object, with CRAM's retry levels (new robot poses, the torso up or to the middle, new
;;;; samples of the search location).

(in-package :cram-fetch-deliver-plans)

(defun reset-or-nil (designator)
  (and designator (desig:reset designator)))

(defun search-for-object (&key object location robot-location &allow-other-keys)
  "Search for OBJECT (an object designator) at LOCATION (a location designator) from
ROBOT-LOCATION (a location designator of base poses). Retries: a new robot pose (5) on a
navigation collision, a looking or a perception failure, raising the torso first; the torso to
the middle (1) on a perception failure; a new sample of LOCATION (2, then 3 around the whole
search). Returns the perceived object designator; SEARCHING-FAILED when all are used up."
  (let ((?object object)
        (?search-location (reset-or-nil location))
        (?robot-location (reset-or-nil robot-location)))
    (cpl:with-retry-counters ((designator-retries 1))
      (cpl:with-failure-handling
          ((desig:designator-error (e)
             (cpl:do-retry designator-retries
               (log-fd :warn 'search-for-object "Desig ~a could not be resolved: ~a~%Retrying."
                       ?search-location e)
               (setf ?search-location (reset-or-nil ?search-location))
               (cpl:retry))
             (cpl:fail 'common-fail:searching-failed
                       :description (format nil "Searching for ~a: a designator could not be ~
                                                 resolved: ~a" (object-text ?object) e))))
        (cpl:with-retry-counters ((outer-location-retries 3))
          (cpl:with-failure-handling
              ((common-fail:object-nowhere-to-be-found (e)
                 (common-fail:retry-with-loc-designator-solutions
                     ?search-location outer-location-retries
                     (:error-object-or-string e :warning-namespace (fd-plans search-for-object)
                      :reset-designators (remove nil (list ?robot-location))
                      :rethrow-failure 'common-fail:searching-failed
                      :distance-threshold 0.1)
                   ;; the reset robot location, relative to the new search location sample
                   (setf ?robot-location (and ?robot-location
                                              (desig:current-desig ?robot-location))))))
            (cpl:with-retry-counters ((robot-location-retries 5))
              (cpl:with-failure-handling
                  (((or common-fail:navigation-goal-in-collision
                        common-fail:looking-high-level-failure
                        common-fail:perception-low-level-failure) (e)
                     (common-fail:retry-with-loc-designator-solutions
                         ?robot-location robot-location-retries
                         (:error-object-or-string e :warning-namespace (fd-plans search-for-object)
                          :reset-designators (remove nil (list ?search-location))
                          :rethrow-failure 'common-fail:object-nowhere-to-be-found)
                       (exe:perform (desig:an action (type moving-torso) (joint-angle upper-limit)
                                              (goal (cpoe:torso-at :upper-limit)))))))
                (let ((?location ?robot-location))
                  (exe:perform (desig:an action (type navigating) (location ?location))))
                (cpl:with-retry-counters ((torso-retries 1))
                  (cpl:with-failure-handling
                      ((common-fail:perception-low-level-failure (e)
                         (cpl:do-retry torso-retries
                           (log-fd :warn 'search-for-object "~a~%Torso to the middle." e)
                           (exe:perform (desig:an action (type moving-torso) (joint-angle middle)
                                                  (goal (cpoe:torso-at :middle))))
                           (cpl:retry))))
                    (cpl:with-retry-counters ((search-location-retries 2))
                      (cpl:with-failure-handling
                          (((or common-fail:perception-low-level-failure
                                common-fail:looking-high-level-failure) (e)
                             (common-fail:retry-with-loc-designator-solutions
                                 ?search-location search-location-retries
                                 (:error-object-or-string e
                                  :warning-namespace (fd-plans search-for-object)
                                  :reset-designators (remove nil (list ?robot-location))))))
                        (let ((?target ?search-location))
                          (exe:perform (desig:an action (type turning-towards) (target ?target))))
                        (exe:perform (desig:an action (type perceiving) (object ?object)))))))))))))))

(defun object-text (object)
  (or (designator-object-name object)
      (let ((type (and (typep object 'desig:object-designator) (prop object :type))))
        (if type (format nil "a ~(~a~)" type) object))))

(defun searching-robot-location (object location)
  "CRAM's default base location of a search: where the robot sees LOCATION and OBJECT."
  (let ((?robot (robot-name)) (?location location) (?object object))
    (desig:a location (visible-for ?robot) (location ?location) (object ?object))))
