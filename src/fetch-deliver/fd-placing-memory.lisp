;;;; Where the robot stood when it put an object down. A delivery that succeeds remembers the
;;;; base pose, the arm and the object's pose; a later fetch of the same, unmoved object offers
;;;; that base pose as the first solution of its robot location (reachable-for ... (object O)),
;;;; ahead of the costmap's samples. The hand that put the object there came and left along
;;;; the poses a grasp of it goes through, so that pose is the likeliest to reach it again, also
;;;; when the objects around it leave few others. The pose is only offered: the navigation
;;;; pre-check still checks it as any other.

(in-package :cram-fetch-deliver-plans)

(defparameter *placed-object-tolerance* 0.01d0
  "Metres an object may have moved since it was put down for the base pose it was put down from
to be offered again.")

(defvar *placing-memory* (make-hash-table :test 'eq :weakness :key :synchronized t)
  "Bullet world -> (EQ hash table: object name -> PLACING-RECORD) of the deliveries done in
that belief state. A world no one holds any more leaves it; each world keeps one record per
object name, so campaigns do not grow it.")

(defstruct (placing-record (:conc-name placing-))
  "What a delivery left behind: the robot's base pose (map) and the arm it put the object down
with, and the object's map position right after."
  base-pose arm object-position)

(defun world-placing-records (&optional (world btr:*current-bullet-world*) create)
  (or (gethash world *placing-memory*)
      (and create (setf (gethash world *placing-memory*) (make-hash-table :test 'eq)))))

(defun remember-placing (object arm &optional base-pose)
  "Record that OBJECT (a designator or name) was just put down with ARM from BASE-POSE (map;
NIL: where the robot stands now)."
  (let* ((name (designator-object-name object))
         (o (and name (btr:object btr:*current-bullet-world* name)))
         (robot (btr:get-robot-object)))
    (when (and o robot)
      (setf (gethash name (world-placing-records btr:*current-bullet-world* t))
            (make-placing-record :base-pose (or base-pose (btr:pose robot)) :arm arm
                                 :object-position (cl-transforms:origin (btr:pose o)))))))

(defun forget-placings (&optional (world btr:*current-bullet-world*))
  "Forget every base pose remembered for the objects put down in WORLD."
  (remhash world *placing-memory*))

(defun placing-record (object)
  "The PLACING-RECORD of OBJECT (a designator or name) when it has not moved by more than
*PLACED-OBJECT-TOLERANCE* since it was put down and no hand holds it; else NIL."
  (let* ((name (designator-object-name object))
         (records (world-placing-records))
         (record (and name records (gethash name records)))
         (o (and record (btr:object btr:*current-bullet-world* name))))
    (when (and o (not (object-held-p name))
               (< (cl-transforms:v-dist (cl-transforms:origin (btr:pose o))
                                        (placing-object-position record))
                  *placed-object-tolerance*))
      record)))

(defun placed-from-location-generator (designator)
  "Location generator: for a robot location (REACHABLE-FOR R) with (OBJECT O), the base pose O
was put down from, while O stands where it was put (PLACING-RECORD); no candidate otherwise."
  (let ((object (and (typep designator 'desig:location-designator)
                     (prop designator :reachable-for)
                     (prop designator :object))))
    (let ((record (and (typep object 'desig:object-designator) (placing-record object))))
      (when record
        (let ((arm (prop designator :arm)))
          (when (or (null arm) (eq arm (placing-arm record)))
            (list (cl-transforms-stamped:pose->pose-stamped
                   cram-tf:*fixed-frame* 0d0 (placing-base-pose record)))))))))

(defun placed-from-location (object arms)
  "A location designator of the base pose OBJECT was put down from (PLACING-RECORD), when it was
put down with one of ARMS (NIL: any); else NIL. The fetch that takes it back drives there first,
with the navigation pre-check (seeing and grasping it from there) as the judge: the costmap's
line-of-sight validator, which would turn the pose down where a neighbour hides a side of the
object, has no say."
  (let ((record (placing-record object)))
    (when (and record (or (null arms) (member (placing-arm record) arms)))
      (let ((?pose (cl-transforms-stamped:pose->pose-stamped
                    cram-tf:*fixed-frame* 0d0 (placing-base-pose record))))
        (desig:a location (pose ?pose))))))

(desig:register-location-generator 12 placed-from-location-generator
  "For a fetch's robot location, the base pose the object was put down from (while it has not
moved since), before the costmap's samples.")
