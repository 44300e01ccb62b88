;;;; Room for what comes next. A table is set object by object, and each object's place is
;;;; chosen when it is put down: the cereal, put down at just any place that passes, can take
;;;; the last place within reach where the milk may go (both go within 0.2 m of the table's
;;;; centre, on its front half), and a bowl put down near the table's edge leaves the spoon,
;;;; which goes right of it, no place at all. Of the places that pass the placing pre-check,
;;;; the first one that leaves each later object some room is taken.

(in-package :cram-fetch-deliver-plans)

(defvar *deliveries-to-come* '()
  "The object types (keywords) that will be transported after the current object, in the same
context, as a table is set object by object (the household demo binds it). A transport leaves
room for those of them that go to places on a surface (*PLACES-TO-LEAVE*).")

(defvar *places-to-leave* '()
  "Location designators of places on a surface that objects put down after the current one
will need (the destinations of *DELIVERIES-TO-COME*). While it is not empty, the placing
pre-check (CHECK-PLACING-COLLISIONS) takes, of the samples that pass, the first that leaves
each of these places room within the robot's reach (ROOM-LEFT); when none leaves every place
room, the one that leaves the most places room.")

(defparameter *room-needed* 0.01d0
  "Square metres of free places (cells of a later object's costmap within the robot's reach)
that count as room for that object: 100 cm², so that the later object's own checks (reach,
collisions, grasping it again) still find a place among them.")

(defun later-places (destination context)
  "The destinations in CONTEXT (from the object knowledge) of *DELIVERIES-TO-COME* that are
places on a surface (not stable, not in a container, as the re-grasp check's targets) other
than DESTINATION itself."
  (loop for type in *deliveries-to-come*
        for place = (ignore-errors
                     (man-int:get-object-destination type (environment-name) nil context))
        when (and place (not (eq place destination)) (surface-place-p place))
          collect place))

(defparameter *room-reach* 0.85d0
  "Metres (horizontally) from the robot's base within which a later object's free places count
as room for it (ROOM-LEFT): farther places are within the costmaps' reach but seldom within
the arm's once the object must also be grasped there again.")

(defun free-area (location base)
  "The square metres of free cells (above 0) of the costmap of the location designator
LOCATION within *ROOM-REACH* of the map point BASE; the costmap is computed for this count only
and not kept."
  (unwind-protect
       (let* ((costmap (handler-case (costmap:designator-costmap location)
                         (desig:designator-error () nil)))
              (cells (and costmap
                          (handler-case (costmap:positive-cells-within
                                         costmap (cl-transforms:x base) (cl-transforms:y base)
                                         *room-reach*)
                            (costmap:invalid-probability-distribution () nil)))))
         (if (null cells)
             0d0
             (* (expt (costmap:resolution costmap) 2) cells)))
    (costmap:forget-designator-costmap location)))

(defun room-left (object candidate)
  "With OBJECT (held) put down at the current solution of the location designator CANDIDATE,
how many of *PLACES-TO-LEAVE* keep at least *ROOM-NEEDED* of free places within *ROOM-REACH*
of the robot's base where it stands."
  (let ((base (cl-transforms-stamped:pose->pose-stamped
               cram-tf:*fixed-frame* 0d0 (btr:pose (btr:get-robot-object))))
        (pose (pp-plans::placing-target-pose
               object (pp-plans:object-designator-type object) candidate)))
    (call-with-object-let-go-at
     object pose
     (lambda (o)
       (declare (ignore o))
       (count-if (lambda (place)
                   (>= (free-area (target-reachable-from place base)
                                  (cl-transforms:origin base))
                       *room-needed*))
                 *places-to-leave*)))))

(defvar *require-room* nil
  "When true, the placing pre-check takes only a sample that leaves every one of
*PLACES-TO-LEAVE* room: NAVIGATE first looks for a base pose with such a sample, and only when
there is none for one with the best sample there is.")

(defun find-placing-sample (predicate target count &key score best require-best final)
  "The first of up to COUNT solutions of the location designator TARGET (each a designator of
its equation chain), drawn one at a time in the costmap's order, that satisfies PREDICATE and
FINAL (NIL: none), or NIL. With SCORE (a function of a solution, a number), the first one that
satisfies them and scores BEST, else (unless REQUIRE-BEST) the one with the highest score among
all COUNT solutions that satisfies them, the first of those with that score. Second value: that
one even under REQUIRE-BEST, where it is not looked for at once but given as a function of no
arguments that finds it (NIL when no solution satisfied PREDICATE), for a caller that may never
need it. FINAL, the dearer part of the test, is asked of a solution that satisfies PREDICATE only
when it would be taken: at once when it scores BEST (or without SCORE), and of the others only
once no solution scores BEST, the highest scores first, until one passes."
  (let ((others '()))                   ; (solution score) passing PREDICATE, not scoring BEST
    (flet ((final-p (current) (or (null final) (funcall final current))))
      (loop repeat count
            for current = target then (desig:next-solution current)
            while current
            when (funcall predicate current)
              do (let ((s (and score (funcall score current))))
                   (if (or (null score) (and best (>= s best)))
                       (when (final-p current)
                         (return-from find-placing-sample current))
                       (push (list current s) others))))
      ;; the highest score first, the earlier first among equal scores
      (let ((ranked (stable-sort (nreverse others) #'> :key #'second)))
        (flet ((highest () (loop for (current) in ranked when (final-p current) return current)))
          (cond ((null ranked) (values nil nil))
                (require-best (values nil #'highest))
                (t (let ((found (highest))) (values found found)))))))))
