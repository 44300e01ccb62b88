;;;; Geometric reasoning on a world: contacts, stability, support, above/below.

(in-package :cram-bullet-reasoning)

(defun contact-records (world &optional object except (threshold 0d0))
  "Contacts of WORLD (or of OBJECT only, leaving out those with the objects of EXCEPT) as
\(object-a link-a object-b link-b) with objects and link names (NIL for plain bodies): the
pairs whose distance is at most THRESHOLD (0: touching; -0.01: reaching 1 cm into each other)."
  (check-world world 'contact-records)
  (let* ((w (world-handle world))
         (raw (if object
                  (with-live-object (object 'contacts)
                    (native:object-contacts w (object-handle object) :threshold threshold
                                            :except (mapcar #'object-handle except)))
                  (native:world-contacts w :threshold threshold))))
    (loop for (ha la hb lb) in raw
          for a = (object-by-handle world ha)
          for b = (object-by-handle world hb)
          when (and a b)
            collect (list a (link-name-of a la) b (link-name-of b lb)))))

(defun link-name-of (object index)
  (and (typep object 'robot-object) (>= index 0)
       (aref (km-link-names (%model object)) index)))

(defun find-all-contacts (&optional (world *current-bullet-world*))
  "Every pair of object names in contact in WORLD, each pair once: ((a b) ...)."
  (let ((pairs '()))
    (loop for (a nil b nil) in (contact-records world)
          for pair = (list (name a) (name b))
          unless (or (member pair pairs :test #'equal)
                     (member (reverse pair) pairs :test #'equal))
            do (push pair pairs))
    (nreverse pairs)))

(defun find-objects-in-contact (world object)
  "Names of the objects touching OBJECT (an object or name) in WORLD."
  (let ((o (ensure-object world object)))
    (remove-duplicates
     (loop for (a nil b nil) in (contact-records world o)
           collect (name (if (eq a o) b a)))
     :from-end t)))

(defun contact-links (world object other)
  "Links of OBJECT (articulated) or OTHER touched where OBJECT and OTHER are in contact, as a
list of (object-link other-link); NIL when they do not touch."
  (let ((o (ensure-object world object)) (p (ensure-object world other)))
    (loop for (a la b lb) in (contact-records world o)
          when (eq b p) collect (list la lb)
          when (and (eq a p) (eq b o)) collect (list lb la))))

(defun objects-in-contact-p (world object other)
  "True when OBJECT and OTHER (objects or names) touch in WORLD."
  (and (contact-links world object other) t))

(defun robot-colliding-objects-without-attached (&optional (world *current-bullet-world*)
                                                   (robot (get-robot-object world)))
  "Names of the objects the robot collides with, leaving out its attached objects and the floor
(the floor does not collide with the robot by its collision filter)."
  (let ((attached (mapcar #'first (%attached robot))))
    (remove-if (lambda (n) (member n attached)) (find-objects-in-contact world robot))))

(defun object-not-in-collision (world object)
  "True when OBJECT touches nothing but objects attached to it or to what it is attached to."
  (let* ((o (ensure-object world object))
         (allowed (loop for r in (objects world)
                        when (and (typep r 'robot-object) (object-attached r o))
                          collect (name r)
                        when (and (typep o 'robot-object) (eq r o))
                          append (mapcar #'first (%attached o)))))
    (null (set-difference (find-objects-in-contact world o) allowed))))

(defun pose-distance (p1 p2)
  "(values metres radians) between two poses."
  (values (cl-transforms:v-dist (cl-transforms:origin p1) (cl-transforms:origin p2))
          (cl-transforms:angle-between-quaternions (cl-transforms:orientation p1)
                                                   (cl-transforms:orientation p2))))

(defparameter *stable-time* 5 "Seconds STABLE simulates.")
(defparameter *stable-distance* 0.005d0 "Largest displacement (m) of a stable object.")
(defparameter *stable-angle* 0.15d0 "Largest rotation (rad) of a stable object.")

(defun stable-p (world &rest names)
  "True when the objects NAMES (default: every item) of WORLD move less than 5 mm and 0.15 rad
during 5 s of simulation of a copy of WORLD."
  (let* ((names (or names (loop for o in (objects world) when (typep o 'item) collect (name o))))
         (before (mapcar (lambda (n) (pose (object-or-fail world n))) names)))
    (with-copied-world (world)
      (simulate *current-bullet-world* *stable-time*)
      (loop for n in names for p in before
            always (multiple-value-bind (d a) (pose-distance p (pose (object *current-bullet-world* n)))
                     (and (< d *stable-distance*) (< a *stable-angle*)))))))

(defun aabb-center-z (object &optional link)
  "Height of the centre of the bounding box of OBJECT (or of its link named LINK)."
  (multiple-value-bind (lo hi) (aabb object (and link (link-index object link)))
    (/ (+ (cl-transforms:z lo) (cl-transforms:z hi)) 2)))

(defun above-p (world a b)
  "True when the bounding box centre of A is higher than that of B."
  (> (aabb-center-z (ensure-object world a)) (aabb-center-z (ensure-object world b))))

(defun below-p (world a b)
  "True when the bounding box centre of A is lower than that of B."
  (< (aabb-center-z (ensure-object world a)) (aabb-center-z (ensure-object world b))))

(defun supported-by-p (world object support)
  "True when OBJECT touches SUPPORT and is above the part it touches (for an articulated
SUPPORT, the touched link, not the whole environment)."
  (let ((o (ensure-object world object)) (s (ensure-object world support)))
    (loop for (lo ls) in (contact-links world o s)
            thereis (> (aabb-center-z o lo) (aabb-center-z s ls)))))

;;; ---- snapshots of a world (pose and joint state, not geometry) ---------------------------------

(defun world-state (&optional (world *current-bullet-world*))
  "A snapshot of every object's pose and every articulated object's joint positions."
  (mapcar (lambda (o)
            (list (name o) (pose o)
                  (and (typep o 'robot-object) (joint-states o))
                  (and (typep o 'robot-object) (copy-list (%attached o)))))
          (objects world)))

(defun restore-world-state (state &optional (world *current-bullet-world*))
  "Put the objects of WORLD back to STATE (from WORLD-STATE); objects added since stay."
  (unless (typep world 'bt-reasoning-world)
    (btr-fail "RESTORE-WORLD-STATE: world ~s, expected a Bullet world" world))
  (unless (and (listp state)
               (every (lambda (e) (and (consp e) (eql (length e) 4) (symbolp (first e)))) state))
    (btr-fail "RESTORE-WORLD-STATE: state ~s, expected a list from WORLD-STATE of ~
(name pose joint-states attachments) entries"
              state))
  (dolist (entry state)
    (destructuring-bind (n p joints attached) entry
      (let ((o (object world n)))
        (when o
          (when (typep o 'robot-object)
            (when joints (set-robot-state-from-joints joints o))
            (setf (%attached o) attached))
          (setf (pose o) p)))))
  world)

(defun get-world-objects-pose-info (&optional (world *current-bullet-world*))
  "Alias of WORLD-STATE (CRAM's name)."
  (world-state world))

(defun restore-world-poses (state &optional (world *current-bullet-world*))
  "Alias of RESTORE-WORLD-STATE (CRAM's name)."
  (restore-world-state state world))

(defmacro with-stored-world ((&optional (world '*current-bullet-world*)) &body body)
  "Run BODY, then put WORLD's objects back to the poses and joint states they had before."
  (let ((w (gensym "W")) (s (gensym "STATE")))
    `(let* ((,w ,world) (,s (world-state ,w)))
       (unwind-protect (progn ,@body)
         (restore-world-state ,s ,w)))))
