;;;; The contacts a motion is meant to make, one notion for both checks of the simulated robot:
;;;; the collision check at a key pose (ROBOT-COLLISIONS) and the sweep check between key poses
;;;; (ROBOT-SWEEPS). Plans declare them in two ways: the pick-and-place plans name the objects a
;;;; hand closes in on (*GRASPED-OBJECTS*, with the container links it may touch,
;;;; *GRASP-CONTAINER-LINKS*) and the held objects being put down (*PLACED-OBJECTS*); any plan
;;;; may add (MOVING HIT) pairs (*SWEEP-ALLOWED-CONTACTS*, WITH-ALLOWED-SWEEP-CONTACTS).
;;;; INTENDED-CONTACTS turns all of them into (MOVING HIT) pairs, which both checks leave out.

(in-package :cram-urdf-projection)

(defvar *grasped-objects* '()
  "The names of the objects the robot's hands are closing in on (set by the picking-up plan
around its grasping step): contacts of the hand links with them are the grasp, not collisions,
at a key pose or on the way.")

(defvar *placed-objects* '()
  "The names of the held objects being put down (set by the placing plan around its putting
step): their contacts with the surface they are put on are the placing, not collisions.")

(defvar *grasp-container-links* '()
  "The environment links the hands may touch while closing in on *GRASPED-OBJECTS*: the
container the object lies in (its board, walls and bottom).")

(defvar *sweep-allowed-contacts* '()
  "Contacts motions are meant to make, left out of the sweep and the collision checks: a list
of (MOVING HIT). MOVING is a link name of the robot (a string), the name of an object carried by
the robot (a symbol), or T for any; HIT is an object name (a symbol), (object-name link-name), or
T for anything. Bind it (WITH-ALLOWED-SWEEP-CONTACTS) around motions that touch on purpose, e.g.
a hand pulling a drawer handle: ((\"r_gripper_palm_link\" (:iai-kitchen \"drawer_handle\"))).")

(defmacro with-allowed-sweep-contacts ((&rest entries) &body body)
  "Run BODY with the (MOVING HIT) ENTRIES (evaluated, see *SWEEP-ALLOWED-CONTACTS*) added to
the contacts motions are meant to make."
  `(let ((*sweep-allowed-contacts* (append (list ,@entries) *sweep-allowed-contacts*)))
     ,@body))

(defun all-hand-links (robot)
  "The link names of every hand of ROBOT."
  (loop for arm in (ignore-errors (robot-arms))
        append (ignore-errors (hand-links arm robot))))

(defvar *last-intended-contacts* nil
  "(key . pairs): the last answer of INTENDED-CONTACTS and what it was made of.")

(defun intended-contacts (robot)
  "The (MOVING HIT) pairs ROBOT's motion is meant to make now: *SWEEP-ALLOWED-CONTACTS*, each hand
link with each of *GRASPED-OBJECTS* and with each of *GRASP-CONTAINER-LINKS* of the environment,
and each of *PLACED-OBJECTS* with anything. The last answer is kept while it is made of the
same lists, robot, environment and facts (not to be modified)."
  (let ((environment (and *grasp-container-links* (btr:get-environment-object (btr:world robot))))
        (last *last-intended-contacts*))
    (destructuring-bind (&optional r e g sweep grasped containers placed) (car last)
      (if (and last (eq r robot) (eq e environment) (eql g (prolog:database-generation))
               (eq sweep *sweep-allowed-contacts*) (eq grasped *grasped-objects*)
               (eq containers *grasp-container-links*) (eq placed *placed-objects*))
          (cdr last)
          (let ((pairs (make-intended-contacts robot environment)))
            (setf *last-intended-contacts*
                  (cons (list robot environment (prolog:database-generation) *sweep-allowed-contacts*
                              *grasped-objects* *grasp-container-links* *placed-objects*)
                        pairs))
            pairs)))))

(defun make-intended-contacts (robot environment)
  (let ((hands (and (or *grasped-objects* *grasp-container-links*) (all-hand-links robot))))
    (append *sweep-allowed-contacts*
            (loop for object in *grasped-objects*
                  append (loop for link in hands collect (list link object)))
            (and environment
                 (loop for container-link in *grasp-container-links*
                       append (loop for link in hands
                                    collect (list link (list (btr:name environment) container-link)))))
            (loop for object in *placed-objects* collect (list object t)))))

(defun contact-pair-matches-p (entry moving moving-link hit hit-link)
  "True when the (MOVING HIT) ENTRY covers the contact of MOVING (the robot's link MOVING-LINK,
or a carried object) with HIT (its link HIT-LINK, or NIL)."
  (and (consp entry) (consp (cdr entry))
       (destructuring-bind (m h) entry
         (and (cond ((eq m t) t)
                    ((stringp m) (and moving-link (string= m moving-link)))
                    (t (and (null moving-link) (eq m (btr:name moving)))))
              (cond ((eq h t) t)
                    ((symbolp h) (eq h (btr:name hit)))
                    ((consp h) (and (eq (first h) (btr:name hit)) hit-link (stringp (second h))
                                    (string= (second h) hit-link)))
                    (t nil))))))

(defun intended-contact-p (entries moving moving-link hit hit-link)
  "True when one of the (MOVING HIT) ENTRIES (INTENDED-CONTACTS) covers the contact of MOVING
\(MOVING-LINK of the robot, or NIL for a carried object) with HIT (HIT-LINK of it, or NIL)."
  (loop for entry in entries
        thereis (contact-pair-matches-p entry moving moving-link hit hit-link)))
