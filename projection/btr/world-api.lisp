;;;; More of CRAM's BTR API: WITH-CURRENT-BULLET-WORLD, PROLOG-?W, the CLEAR-BULLET-WORLD
;;;; predicate, OBJ-POSE-ON, ROBOT-ATTACHED-OBJECTS-IN-COLLISION.

(in-package :cram-bullet-reasoning)

(defmacro with-current-bullet-world (world &body body)
  "Evaluate BODY with *CURRENT-BULLET-WORLD* bound to WORLD (a BT-REASONING-WORLD)."
  (let ((w (gensym "WORLD")))
    `(let ((,w ,world))
       (unless (typep ,w 'bt-reasoning-world)
         (btr-fail "WITH-CURRENT-BULLET-WORLD: ~s is not a Bullet world" ,w))
       (let ((*current-bullet-world* ,w))
         ,@body))))

(defun world-variable (clauses)
  "The variable named ?W that CLAUSES use (of whatever package), or BTR's ?W."
  (labels ((find-w (x)
             (cond ((and (symbolp x) (string= (symbol-name x) "?W")) x)
                   ((consp x) (or (find-w (car x)) (find-w (cdr x)))))))
    (or (find-w clauses) '?w)))

(defun prolog-?w-query (clauses)
  "The query of PROLOG-?W: (and (bullet-world ?w) clause...)."
  (list* 'and (list 'bullet-world (world-variable clauses)) clauses))

(defmacro prolog-?w (&body clauses)
  "Prove the CLAUSES (evaluated: each gives a goal) with ?W bound to the current Bullet world,
as (prolog `(and (bullet-world ?w) ,@clauses)); returns PROLOG's lazy list of solutions. ?W
may be written in any package."
  `(prolog (prolog-?w-query (list ,@clauses))))

(defun fresh-world ()
  "A new, empty BT-REASONING-WORLD."
  (make-instance 'bt-reasoning-world))

(defun clear-current-world ()
  "Make *CURRENT-BULLET-WORLD* a new, empty world; return it."
  (setf *current-bullet-world* (fresh-world)))

(def-fact-group bullet-world-api-facts ()
  ;; (clear-bullet-world): the current world becomes a new, empty one
  (<- (clear-bullet-world)
    (lisp-fun clear-current-world ?_))
  ;; (clear-bullet-world ?world): ?world is a new, empty world
  (<- (clear-bullet-world ?world)
    (not (bound ?world))
    (lisp-fun fresh-world ?world)))

(defun obj-pose-on (pose object)
  "A pose for OBJECT (an object of a world) with POSE's orientation such that the bottom centre
of OBJECT's bounding box (as it is oriented now) lies at POSE's position."
  (let ((pose (ensure-pose pose "OBJ-POSE-ON pose")))
    (unless (typep object 'object)
      (btr-fail "OBJ-POSE-ON: ~s is not an object of a Bullet world" object))
    (multiple-value-bind (lo hi) (aabb object)
      (let* ((center (cl-transforms:v* (cl-transforms:v+ lo hi) 0.5d0))
             (offset (cl-transforms:v- (cl-transforms:origin (pose object))
                                       (cl-transforms:make-3d-vector
                                        (cl-transforms:x center) (cl-transforms:y center)
                                        (cl-transforms:z lo)))))
        (cl-transforms:copy-pose pose :origin (cl-transforms:v+ (cl-transforms:origin pose)
                                                                 offset))))))

(defun robot-attached-objects-in-collision (&optional (world *current-bullet-world*)
                                              (robot (get-robot-object world)))
  "True when an object attached to ROBOT touches something other than ROBOT and the objects it
is itself attached to (items attached to each other may touch)."
  (unless (typep robot 'robot-object)
    (btr-fail "ROBOT-ATTACHED-OBJECTS-IN-COLLISION: no robot object (got ~s)" robot))
  (loop for (name) in (%attached robot)
        for held = (object world name)
        thereis (and held
                     (let ((allowed (cons (name robot) (mapcar #'first (attached-objects held)))))
                       (set-difference (find-objects-in-contact world held) allowed)))))

(setf (documentation 'clear-bullet-world 'function)
      "Prolog predicate (clear-bullet-world): the current world becomes a new, empty one;
(clear-bullet-world ?world): ?world is a new, empty world.")

(setf (documentation 'item-types 'function) "The item types (keywords) of an object, e.g. (:BOTTLE)."
      (documentation 'name 'function) "The name of an object of a Bullet world (a symbol)."
      (documentation 'object-handle 'function) "The native handle of an object of a Bullet world."
      (documentation 'object-kind 'function) "The ADD-OBJECT type keyword an object was made with."
      (documentation 'object-spec 'function) "The ADD-OBJECT keys an object was made with."
      (documentation 'world 'function) "The Bullet world an object lives in."
      (documentation 'world-handle 'function) "The native handle of a Bullet world."
      (documentation 'world-lock 'function) "The lock that serialises the native calls on a world.")
