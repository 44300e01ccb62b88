;;;; The costmap metadata predicates.
;;;;
;;;; They take no robot argument: an environment, a robot description or the user declares
;;;; them in a fact group that lists them as extendable, e.g.
;;;;   (def-fact-group my-metadata (costmap:costmap-size) (<- (costmap:costmap-size 12 12)))
;;;; and consumers take the first solution.
;;;;
;;;; Several robot descriptions may be loaded in one image.  A description that should not
;;;; impose its values on the others states them keyed by its robot name through
;;;; ROBOT-COSTMAP-METADATA, e.g. (<- (robot-costmap-metadata :pr2 (costmap-padding 0.3))).
;;;; The clauses below come before every other group's clauses and answer from the keyed
;;;; facts of the current robot (ROB-INT:*ROBOT-NAME*) first; with no current robot, from
;;;; the keyed facts of any robot.  Unkeyed clauses of later groups follow.
;;;;
;;;; Before all of these come the user's own metadata: the tutorials have the user type
;;;;   (def-fact-group costmap-metadata () (<- (costmap-size 12 12)) ...)
;;;; in their own package (e.g. BTW-TUT), where COSTMAP-SIZE is that package's symbol, not
;;;; this package's.  A predicate of the same name as a metadata predicate, defined by a fact
;;;; group in any other package, is the user stating the value: it answers first, so the
;;;; costmaps use what the user typed (see USER-COSTMAP-METADATA-FACTS).

(in-package :cram-location-costmap)

(defvar *reading-user-metadata* nil
  "True while the user's metadata predicates are queried (a user clause that asks the
metadata interface again then gets no user answer instead of recursing without end).")

(defvar *user-metadata-candidates* (make-hash-table :test 'eq :synchronized t)
  "Metadata functor -> (generation package-count . symbols): the user's predicates named like
it (USER-METADATA-CANDIDATES), as found when the Prolog database had that generation and the
image that many packages.")

(defun user-metadata-candidates (functor)
  "The predicates named like FUNCTOR in other packages that have clauses, packages taken in
name order. Looked up again only after the Prolog database or the set of packages changed."
  (let* ((generation (prolog:database-generation))
         (packages (list-all-packages))
         (count (length packages))
         (cached (gethash functor *user-metadata-candidates*)))
    (if (and cached (eql (first cached) generation) (eql (second cached) count))
        (cddr cached)
        (let ((name (symbol-name functor)) (candidates '()))
          (dolist (package (sort packages #'string< :key #'package-name))
            (let ((symbol (find-symbol name package)))
              (when (and symbol (not (eq symbol functor)) (not (member symbol candidates))
                         (prolog:predicate-clauses symbol))
                (push symbol candidates))))
          (setf candidates (nreverse candidates))
          (setf (gethash functor *user-metadata-candidates*) (list* generation count candidates))
          candidates))))

(defun user-costmap-metadata-facts (fact)
  "The facts (FUNCTOR value...) stated by the user for the metadata FACT (its functor is one
of this package's metadata predicates, its arguments are only counted): the answers of every
predicate named like FUNCTOR in another package that has clauses, i.e. a fact group the user
wrote with the short names in their own package.  Packages are taken in name order."
  (unless (or *reading-user-metadata* (not (consp fact)) (not (symbolp (car fact))))
    (let* ((functor (car fact))
           (arity (length (cdr fact)))
           (candidates (user-metadata-candidates functor)))
      (when candidates
        (let ((*reading-user-metadata* t)
              (vars (loop for i below arity collect (intern (format nil "?U~d" i) :cram-location-costmap))))
          (loop for symbol in candidates
                append (loop for answer in (cut:force-ll (prolog `(,symbol ,@vars)))
                             collect (cons functor (mapcar (lambda (v) (cut:var-value v answer)) vars)))))))))

(defparameter *metadata-interface-goals* '(user-costmap-metadata current-robot-costmap-metadata)
  "The functors of the goals by which this package's own rules answer a metadata predicate.")

(defun fact-clauses-p (functor &key (interface-rules nil))
  "True when every clause of FUNCTOR is a fact, a rule whose body is (fail), or, with
INTERFACE-RULES, one of this package's rules answering through *METADATA-INTERFACE-GOALS*;
and FUNCTOR has no Lisp handler: its answers depend on nothing but the database."
  (let ((pred (gethash functor prolog::*predicates*)))
    (and (or (null pred) (null (prolog::pred-handler pred)))
         (every (lambda (clause)
                  (let ((body (cdr clause)))
                    (or (null body)
                        (and (null (cdr body)) (consp (first body))
                             (or (string= (symbol-name (car (first body))) "FAIL")
                                 (and interface-rules
                                      (member (car (first body)) *metadata-interface-goals*)))))))
                (prolog:predicate-clauses functor)))))

(defun interface-only-p (functor)
  "True when FUNCTOR's clauses are all this package's own (the fact group
LOCATION-COSTMAP-METADATA-INTERFACE) and it has no Lisp handler."
  (let ((pred (gethash functor prolog::*predicates*)))
    (and pred (null (prolog::pred-handler pred)) (null (prolog::pred-dynamic pred))
         (every (lambda (source) (eq (car source) 'location-costmap-metadata-interface))
                (prolog::pred-sources pred)))))

(defvar *metadata-facts-verdicts* (make-hash-table :test 'eq :synchronized t)
  "Metadata functor -> (generation . verdict) of METADATA-FROM-FACTS-P.")

(defun metadata-from-facts-p (functor)
  "True when the answers of the metadata predicate FUNCTOR come from facts only: its own
clauses, those of ROBOT-COSTMAP-METADATA and those of the user's predicates named like it
\(USER-METADATA-CANDIDATES) are facts (FACT-CLAUSES-P). Its first answer then stays the same
for the same current robot until the Prolog database changes (clauses a user adds in a new
package change it too)."
  (let* ((generation (prolog:database-generation))
         (cached (gethash functor *metadata-facts-verdicts*)))
    (if (and cached (eql (car cached) generation))
        (cdr cached)
        (let ((verdict (and (every #'interface-only-p *metadata-interface-goals*)
                            (fact-clauses-p functor :interface-rules t)
                            (fact-clauses-p 'robot-costmap-metadata)
                            (every #'fact-clauses-p (user-metadata-candidates functor))
                            t)))
          (setf (gethash functor *metadata-facts-verdicts*) (cons generation verdict))
          verdict))))

(def-fact-group location-costmap-metadata-interface
    (costmap-size costmap-origin costmap-resolution
     costmap-padding costmap-manipulation-padding
     costmap-in-reach-distance costmap-reach-minimal-distance
     visibility-costmap-size orientation-samples orientation-sample-step
     robot-costmap-metadata)

  (<- (robot-costmap-metadata ?robot-name ?metadata-fact) (fail))

  (<- (user-costmap-metadata ?metadata-fact)
    (lisp-fun user-costmap-metadata-facts ?metadata-fact ?facts)
    (member ?metadata-fact ?facts))

  (<- (current-robot-costmap-metadata ?metadata-fact)
    (symbol-value rob-int:*robot-name* ?current)
    (-> (lisp-pred identity ?current)
        (robot-costmap-metadata ?current ?metadata-fact)
        (robot-costmap-metadata ?_ ?metadata-fact)))

  (<- (costmap-size ?width ?height)
    (user-costmap-metadata (costmap-size ?width ?height)))
  (<- (costmap-size ?width ?height)
    (current-robot-costmap-metadata (costmap-size ?width ?height)))
  (<- (costmap-origin ?x ?y)
    (user-costmap-metadata (costmap-origin ?x ?y)))
  (<- (costmap-origin ?x ?y)
    (current-robot-costmap-metadata (costmap-origin ?x ?y)))
  (<- (costmap-resolution ?resolution)
    (user-costmap-metadata (costmap-resolution ?resolution)))
  (<- (costmap-resolution ?resolution)
    (current-robot-costmap-metadata (costmap-resolution ?resolution)))
  (<- (costmap-padding ?padding)
    (user-costmap-metadata (costmap-padding ?padding)))
  (<- (costmap-padding ?padding)
    (current-robot-costmap-metadata (costmap-padding ?padding)))
  (<- (costmap-manipulation-padding ?padding)
    (user-costmap-metadata (costmap-manipulation-padding ?padding)))
  (<- (costmap-manipulation-padding ?padding)
    (current-robot-costmap-metadata (costmap-manipulation-padding ?padding)))
  (<- (costmap-in-reach-distance ?distance)
    (user-costmap-metadata (costmap-in-reach-distance ?distance)))
  (<- (costmap-in-reach-distance ?distance)
    (current-robot-costmap-metadata (costmap-in-reach-distance ?distance)))
  (<- (costmap-reach-minimal-distance ?distance)
    (user-costmap-metadata (costmap-reach-minimal-distance ?distance)))
  (<- (costmap-reach-minimal-distance ?distance)
    (current-robot-costmap-metadata (costmap-reach-minimal-distance ?distance)))
  (<- (visibility-costmap-size ?radius)
    (user-costmap-metadata (visibility-costmap-size ?radius)))
  (<- (visibility-costmap-size ?radius)
    (current-robot-costmap-metadata (visibility-costmap-size ?radius)))
  (<- (orientation-samples ?count)
    (user-costmap-metadata (orientation-samples ?count)))
  (<- (orientation-samples ?count)
    (current-robot-costmap-metadata (orientation-samples ?count)))
  (<- (orientation-sample-step ?angle)
    (user-costmap-metadata (orientation-sample-step ?angle)))
  (<- (orientation-sample-step ?angle)
    (current-robot-costmap-metadata (orientation-sample-step ?angle))))

(rob-int::define-predicate-documentation
  (costmap-size "(costmap-size ?width ?height): the extent of a location costmap in metres.")
  (costmap-origin "(costmap-origin ?x ?y): the map-frame position of the costmap's corner
with the smallest coordinates.")
  (costmap-resolution "(costmap-resolution ?resolution): the costmap cell size in metres.")
  (costmap-padding "(costmap-padding ?padding): the distance the robot base keeps from
obstacles, in metres.")
  (costmap-manipulation-padding "(costmap-manipulation-padding ?padding): the obstacle
distance used for base poses while manipulating, in metres.")
  (costmap-in-reach-distance "(costmap-in-reach-distance ?distance): the farthest distance
from the base at which the robot can reach, in metres.")
  (costmap-reach-minimal-distance "(costmap-reach-minimal-distance ?distance): the nearest
distance from the base at which the robot can reach, in metres.")
  (visibility-costmap-size "(visibility-costmap-size ?radius): the radius of the area around
a target sampled for poses that see it, in metres.")
  (orientation-samples "(orientation-samples ?count): how many base orientations are
generated per sampled position.")
  (orientation-sample-step "(orientation-sample-step ?angle): the angle between consecutive
sampled orientations, in radians.")
  (user-costmap-metadata "(user-costmap-metadata ?metadata-fact): a metadata fact the user
stated with the short names in their own package, e.g. BTW-TUT::COSTMAP-SIZE; it answers
before the robot's own metadata.")
  (robot-costmap-metadata "(robot-costmap-metadata ?robot-name ?metadata-fact): a metadata
fact such as (costmap-padding 0.3) that holds when ?robot-name is the current robot.")
  (current-robot-costmap-metadata "(current-robot-costmap-metadata ?metadata-fact): the
ROBOT-COSTMAP-METADATA facts of the current robot, or of any robot when none is current."))
