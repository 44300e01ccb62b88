;;;; Transporting: make the destination and the source accessible (opening drawers and doors),
;;;; search the object, fetch it, deliver it and close what was opened. Each step is skipped
;;;; when its goal already holds. A failed delivery drops the object at the sink.

(in-package :cram-fetch-deliver-plans)

(defun perform-with-goal (action goal)
  "Perform the action designator ACTION with the occasion GOAL as its goal."
  (exe:perform (desig:copy-designator action :new-description `((:goal ,goal)))))

(defun search-location-action (location)
  (let ((?location location))
    (perform-with-goal (desig:an action (type searching) (location ?location))
                       `(man-int:location-certain ,location))))

(defun accessing-action (location arms)
  (let ((?location location) (?arms arms))
    (perform-with-goal (desig:an action (type accessing) (location ?location)
                                 (desig:when ?arms (arms ?arms)))
                       `(cpoe:location-accessible ,location))))

(defun sealing-action (location arms)
  (let ((?location location) (?arms arms))
    (perform-with-goal (desig:an action (type sealing) (location ?location)
                                 (desig:when ?arms (arms ?arms)))
                       `(cpoe:location-reset ,location))))

(defun transport (&key object context arms grasps search-location delivery-location
                    search-robot-location fetch-robot-location deliver-robot-location
                  &allow-other-keys)
  "Bring OBJECT from SEARCH-LOCATION to DELIVERY-LOCATION (location designators) in CONTEXT:
search the delivery location's reference object when its pose is not certain and make the
location accessible, the same for the search location, search the object, fetch it with ARMS
and GRASPS, deliver it, then seal the search and the delivery location. On DELIVERING-FAILED
the object is dropped at the sink and the failure propagates. The delivery leaves
room for the objects of *DELIVERIES-TO-COME* (*PLACES-TO-LEAVE*)."
  (search-location-action delivery-location)
  (accessing-action delivery-location arms)
  (search-location-action search-location)
  (accessing-action search-location arms)
  (let* ((?object object) (?search-location search-location)
         (?search-robot search-robot-location)
         (?perceived (if (object-held-p object)
                         (desig:current-desig object)
                         (exe:perform
                          (desig:an action (type searching) (object ?object)
                                    (location ?search-location)
                                    (desig:when ?search-robot (robot-location ?search-robot))))))
         (?arms arms) (?grasps grasps) (?fetch-robot fetch-robot-location))
    (perform-with-goal (desig:an action (type fetching) (object ?perceived)
                                 (desig:when ?arms (arms ?arms))
                                 (desig:when ?grasps (grasps ?grasps))
                                 (desig:when ?fetch-robot (robot-location ?fetch-robot)))
                       `(cpoe:object-in-hand ,?perceived))
    (let ((?target delivery-location) (?deliver-robot deliver-robot-location)
          (?held (desig:current-desig ?perceived)))
      (cpl:with-failure-handling
          ((common-fail:delivering-failed (e)
             (log-fd :warn 'transport "~a~%Dropping the object at the sink." e)
             (drop-at-sink)))
        (let ((*places-to-leave* (later-places delivery-location context)))
          (perform-with-goal (desig:an action (type delivering) (object ?held) (target ?target)
                                     (desig:when ?deliver-robot (robot-location ?deliver-robot)))
                             `(cpoe:object-at-location ,?held ,delivery-location))))))
  (sealing-action search-location arms)
  (sealing-action delivery-location arms)
  (desig:current-desig object))
