;;;; Prolog predicates of the belief state: worlds, objects, poses, joints, the assert/retract
;;;; forms, attachments, contacts, stability, support and visibility.

(in-package :cram-bullet-reasoning)

;;; ---- Lisp helpers called from the clauses -------------------------------------------------------

(defun prolog-add-object (world type name pose keys)
  "ASSERT of (object ...): add the object, or teleport it when NAME exists."
  (let ((existing (object world name)))
    (cond (existing (setf (pose existing) pose) existing)
          (t (apply #'add-object world type name pose keys)))))

(defun object-designator-name (world designator)
  "An object name from DESIGNATOR: an object, or a name of WORLD."
  (if (typep designator 'object) (name designator) (name (object-or-fail world designator))))

(defun prolog-set-pose-on (world name pose)
  "Put the object NAME with the bottom of its bounding box on POSE's position."
  (let* ((o (object-or-fail world name))
         (p (ensure-pose pose)))
    (setf (pose o) p)
    (multiple-value-bind (lo) (aabb o)
      (let ((dz (- (cl-transforms:z (cl-transforms:origin p)) (cl-transforms:z lo))))
        (setf (pose o) (cl-transforms:make-pose
                        (cl-transforms:v+ (cl-transforms:origin p) (cl-transforms:make-3d-vector 0 0 dz))
                        (cl-transforms:orientation p)))))
    o))

(defun prolog-attach (world robot link object)
  (let ((r (object-or-fail world robot)))
    (attach-object r (ensure-object world object) :link link)
    t))

(defun prolog-detach (world robot link object)
  (let ((r (object-or-fail world robot)))
    (detach-object r (ensure-object world object) :link (and (stringp link) link))
    t))

(defun attachment-list (world robot)
  "((link object-name) ...) of the articulated object ROBOT (object or name)."
  (let ((r (ensure-object world robot)))
    (when (typep r 'robot-object)
      (mapcar (lambda (a) (list (second a) (first a))) (%attached r)))))

(defun items-of (world) (loop for o in (objects world) when (typep o 'item) collect (name o)))

(defun pose-as-lists (pose)
  (let ((o (cl-transforms:origin pose)) (q (cl-transforms:orientation pose)))
    (list (list (cl-transforms:x o) (cl-transforms:y o) (cl-transforms:z o))
          (list (cl-transforms:x q) (cl-transforms:y q) (cl-transforms:z q) (cl-transforms:w q)))))

(defun object-bottom-pose (object)
  "OBJECT's pose moved down to the bottom of its bounding box."
  (let ((p (pose object)))
    (multiple-value-bind (lo) (aabb object)
      (cl-transforms:make-pose
       (cl-transforms:make-3d-vector (cl-transforms:x (cl-transforms:origin p))
                                     (cl-transforms:y (cl-transforms:origin p))
                                     (cl-transforms:z lo))
       (cl-transforms:orientation p)))))

(defun prolog-set-object-pose (world name pose)
  "ASSERT of (object-pose NAME POSE): teleport the object NAME; an error naming NAME when WORLD
has no such object, or naming POSE when it is not a pose."
  (set-object-pose (ensure-object world name) pose))

(defun prolog-set-joint-state (world robot joint-states)
  "ASSERT of (joint-state ROBOT JOINT-STATES) on the articulated object ROBOT (object or name)."
  (let ((o (ensure-object world robot)))
    (unless (typep o 'robot-object)
      (btr-fail "joint-state: ~s is not an articulated object (it has no joints)" (name o)))
    (set-robot-state-from-joints joint-states o)))

(defun set-object-pose (object pose)
  "Teleport OBJECT to POSE (anything ENSURE-POSE accepts)."
  (setf (pose object) (ensure-pose pose (format nil "pose of ~s" (name object)))))

;;; The rule for errors: the Lisp functions behind predicates that change the world (the assert
;;; and retract forms, SIMULATE, STEP) signal their errors out of the query, as CRAM's assert
;;; handlers do (see PROLOG:PROPAGATE-LISP-ERRORS); query predicates (OBJECT, POSE, CONTACT,
;;; STABLE ...) warn and fail on a Lisp error, failure being their documented answer.
(prolog:propagate-lisp-errors 'prolog-add-object 'remove-object 'prolog-set-object-pose
                              'prolog-set-pose-on 'prolog-set-joint-state 'prolog-attach
                              'prolog-detach 'simulate 'step-world)

;;; ---- worlds and objects ----------------------------------------------------------------------------

(def-fact-group bullet-world-facts (assert retract)
  (<- (bullet-world ?world)
    (symbol-value *current-bullet-world* ?world))

  (<- (debug-window ?world)
    (lisp-fun debug-window ?world ?_))

  (<- (object ?world ?name)
    (bound ?name)
    (lisp-fun object ?world ?name ?o)
    (lisp-pred identity ?o))
  (<- (object ?world ?name)
    (not (bound ?name))
    (lisp-fun object-names ?world ?names)
    (member ?name ?names))

  (<- (%object ?world ?name ?object)
    (object ?world ?name)
    (lisp-fun object ?world ?name ?object))

  (<- (item ?world ?name)
    (%object ?world ?name ?o)
    (lisp-pred typep ?o item))

  (<- (item-type ?world ?name ?type)
    (%object ?world ?name ?o)
    (lisp-fun item-types ?o ?types)
    (member ?type ?types))

  (<- (robot-object ?world ?name)
    (%object ?world ?name ?o)
    (lisp-pred typep ?o robot-object))

  (<- (pose ?world ?name ?pose)
    (%object ?world ?name ?o)
    (lisp-fun pose ?o ?pose))
  (<- (pose ?world ?name ?position ?orientation)
    (pose ?world ?name ?pose)
    (lisp-fun pose-as-lists ?pose (?position ?orientation)))

  (<- (object-pose ?world ?name ?pose)
    (pose ?world ?name ?pose))

  (<- (object-bottom-pose ?world ?name ?pose)
    (%object ?world ?name ?o)
    (lisp-fun object-bottom-pose ?o ?pose))

  (<- (simulate ?world ?seconds)
    (lisp-fun simulate ?world ?seconds ?_))
  (<- (simulate ?world ?seconds ?dt)
    (lisp-fun simulate ?world ?seconds ?dt ?_))
  (<- (step ?world)
    (lisp-fun step-world ?world ?_))
  (<- (step ?world ?dt)
    (lisp-fun step-world ?world ?dt ?_))

  ;; assert and retract: the world first, or inside the term
  (<- (assert ?world (object ?type ?name ?pose . ?keys))
    (lisp-fun prolog-add-object ?world ?type ?name ?pose ?keys ?_))
  (<- (assert (object ?world ?type ?name ?pose . ?keys))
    (assert ?world (object ?type ?name ?pose . ?keys)))
  (<- (retract ?world (object ?name))
    (lisp-fun remove-object ?world ?name ?_))
  (<- (retract (object ?world ?name))
    (retract ?world (object ?name)))

  (<- (assert ?world (object-pose ?name ?pose))
    (lisp-fun prolog-set-object-pose ?world ?name ?pose ?_))
  (<- (assert (object-pose ?world ?name ?pose))
    (assert ?world (object-pose ?name ?pose)))
  (<- (assert ?world (object-pose-on ?name ?pose))
    (lisp-fun prolog-set-pose-on ?world ?name ?pose ?_))
  (<- (assert (object-pose-on ?world ?name ?pose))
    (assert ?world (object-pose-on ?name ?pose)))

  (<- (assert ?world (joint-state ?robot ?joint-states))
    (lisp-fun prolog-set-joint-state ?world ?robot ?joint-states ?_))
  (<- (assert (joint-state ?world ?robot ?joint-states))
    (assert ?world (joint-state ?robot ?joint-states)))

  (<- (assert ?world (attached ?robot ?link ?object))
    (lisp-fun prolog-attach ?world ?robot ?link ?object ?_))
  (<- (assert (attached ?world ?robot ?link ?object))
    (assert ?world (attached ?robot ?link ?object)))
  (<- (retract ?world (attached ?robot ?link ?object))
    (attached ?world ?robot ?link ?object)
    (lisp-fun prolog-detach ?world ?robot ?link ?object ?_))
  (<- (retract ?world (attached ?robot ?object))
    (retract ?world (attached ?robot ?_ ?object)))
  (<- (retract (attached ?world ?robot ?link ?object))
    (retract ?world (attached ?robot ?link ?object)))
  (<- (retract (attached ?world ?robot ?object))
    (retract ?world (attached ?robot ?_ ?object))))

;;; ---- articulated objects ---------------------------------------------------------------------------

(def-fact-group robot-model-facts ()
  (<- (link ?world ?robot ?link)
    (%object ?world ?robot ?o)
    (lisp-pred typep ?o robot-object)
    (lisp-fun link-names ?o ?links)
    (member ?link ?links))

  (<- (link-pose ?world ?robot ?link ?pose)
    (%object ?world ?robot ?o)
    (lisp-pred typep ?o robot-object)
    (-> (bound ?link)
        (true)
        (and (lisp-fun link-names ?o ?links) (member ?link ?links)))
    (lisp-fun link-pose ?o ?link ?pose))

  (<- (joint-state ?world ?robot ?joint ?state)
    (%object ?world ?robot ?o)
    (lisp-pred typep ?o robot-object)
    (-> (bound ?joint)
        (lisp-fun joint-state ?o ?joint ?state)
        (and (lisp-fun joint-states ?o ?states)
             (member (?joint . ?state) ?states))))

  (<- (attached ?world ?robot ?link ?object)
    (bullet-world ?world)
    (robot-object ?world ?robot)
    (lisp-fun attachment-list ?world ?robot ?attachments)
    (-> (and (bound ?object) (lisp-pred typep ?object object))
        (and (lisp-fun name ?object ?object-name)
             (member (?link ?object-name) ?attachments))
        (member (?link ?object) ?attachments)))
  (<- (attached ?world ?robot ?object)
    (attached ?world ?robot ?_ ?object)))

;;; ---- contacts, stability, support ----------------------------------------------------------------------

(def-fact-group physics-facts ()
  (<- (contact ?world ?a ?b)
    (bound ?a)
    (lisp-fun find-objects-in-contact ?world ?a ?touching)
    (member ?b ?touching))
  (<- (contact ?world ?a ?b)
    (not (bound ?a))
    (lisp-fun find-all-contacts ?world ?pairs)
    (or (member (?a ?b) ?pairs)
        (member (?b ?a) ?pairs)))
  (<- (contact ?world ?a ?b ?link)
    (contact ?world ?a ?b)
    (lisp-fun contact-links ?world ?a ?b ?link-pairs)
    (or (member (?link ?_) ?link-pairs)
        (member (?_ ?link) ?link-pairs))
    (lisp-pred identity ?link))

  (<- (object-not-in-collision ?world ?name)
    (object ?world ?name)
    (lisp-pred object-not-in-collision ?world ?name))

  (<- (stable ?world ?name)
    (object ?world ?name)
    (lisp-pred stable-p ?world ?name))
  (<- (stable ?world)
    (lisp-pred stable-p ?world))

  (<- (above ?world ?a ?b)
    (object ?world ?a) (object ?world ?b)
    (lisp-pred above-p ?world ?a ?b))
  (<- (below ?world ?a ?b)
    (object ?world ?a) (object ?world ?b)
    (lisp-pred below-p ?world ?a ?b))

  (<- (supported-by ?world ?object ?support)
    (contact ?world ?object ?support)
    (lisp-pred supported-by-p ?world ?object ?support)))

;;; ---- visibility -------------------------------------------------------------------------------------

(def-fact-group visibility-facts ()
  (<- (visible ?world ?robot ?object)
    (bound ?robot)
    (lisp-fun camera-pose ?robot ?world ?camera)
    (-> (bound ?object)
        (true)
        (and (lisp-fun items-of ?world ?items) (member ?object ?items)))
    (lisp-pred object-visible-p ?world ?camera ?object))

  (<- (occluding-objects ?world ?robot ?object ?occluders)
    (lisp-fun camera-pose ?robot ?world ?camera)
    (lisp-fun occluding-objects ?world ?camera ?object ?occluders)))

;;; ---- world scoping -----------------------------------------------------------------------------------

(def-prolog-handler with-copied-world (bindings ?world &rest goals)
  (let ((copy (copy-world (if (is-var ?world) *current-bullet-world* ?world))))
    (let ((*current-bullet-world* copy))
      (force-ll (prolog `(and ,@goals)
                        (if (is-var ?world) (acons ?world copy nil) nil))))))

(def-prolog-handler with-stored-world (bindings ?world &rest goals)
  (let ((world (if (is-var ?world) *current-bullet-world* ?world)))
    (with-stored-world (world)
      (force-ll (prolog `(and ,@goals))))))

;;; ---- documentation of the predicates -----------------------------------------------------------

(loop for (symbol doc) in
      '((bullet-world "(bullet-world ?world): ?world is *CURRENT-BULLET-WORLD*.")
        (%object "(%object ?world ?name ?object): ?object is the Lisp object called ?name.")
        (item "(item ?world ?name): ?name is a movable item.")
        (retract "(retract ?world (object ?name)), (retract ?world (attached ?robot [?link] ?object)), or the same with the world inside the term: remove from the belief state.")
        (attached "(attached ?world ?robot [?link] ?object): ?object (a name or object) is attached to ?link of ?robot.")
        (link "(link ?world ?robot ?link): ?link is a link name of the articulated object ?robot.")
        (object-pose-on "(assert ?world (object-pose-on ?name ?pose)): put the bottom of ?name on ?pose.")
        (contact "(contact ?world ?a ?b [?link]): ?a and ?b touch (?link: the link of an articulated one).")
        (stable "(stable ?world [?name]): ?name (or every item) moves < 5 mm and 0.15 rad in 5 s of simulation of a copy.")
        (supported-by "(supported-by ?world ?object ?support): ?object touches ?support and lies above the touched part.")
        (above "(above ?world ?a ?b): the bounding box centre of ?a is higher than that of ?b.")
        (below "(below ?world ?a ?b): the bounding box centre of ?a is lower than that of ?b.")
        (visible "(visible ?world ?robot ?object): at least *VISIBILITY-THRESHOLD* of ?object is unoccluded from ?robot's camera.")
        (occluding-objects "(occluding-objects ?world ?robot ?object ?occluders): names of what hides ?object.")
        (object-not-in-collision "(object-not-in-collision ?world ?name): ?name touches only what is attached to it."))
      do (setf (documentation symbol 'function) doc))
