;;;; Prolog interface of the designators: the extendable grounding predicates (which fail until
;;;; other layers add rules) and predicates to inspect designators.

(in-package :cram-designators)

(def-fact-group designator-grounding-interfaces (action-grounding motion-grounding
                                                 location-grounding)
  ;; (action-grounding ?designator ?grounding): ?grounding is (plan-function resolved-designator)
  ;; or (plan-function argument...).
  (<- (action-grounding ?designator ?grounding)
    (fail))
  ;; (motion-grounding ?designator ?grounding): ?grounding is (command argument...).
  (<- (motion-grounding ?designator ?grounding)
    (fail))
  ;; (location-grounding ?designator ?solution): one candidate solution per proof.
  (<- (location-grounding ?designator ?solution)
    (fail))
  (<- (location-grounding ?designator ?pose)
    (loc-desig? ?designator)
    (desig-prop ?designator (:pose ?pose)))
  (<- (location-grounding ?designator ?pose)
    (loc-desig? ?designator)
    (desig-prop ?designator (:poses ?poses))
    (member ?pose ?poses)))

(def-native-predicate desig-prop (m cont designator property)
  ;; (desig-prop ?designator (?key ?value)): each (key value) entry of a bound designator's
  ;; description that unifies with the property, in the description's order; with a keyword key
  ;; the entries of other keys are passed over without being unified (the grounding rules ask
  ;; for one key of each designator they are tried on)
  (let ((d (deref-term designator)))
    (when (typep d 'designator)
      (let* ((p (deref-term property))
             (key (and (consp p) (let ((k (deref-term (car p)))) (and (keywordp k) k)))))
        (unify-each m p (loop for e in (description d)
                              when (and (consp e) (consp (cdr e)) (null (cddr e))
                                        (or (null key) (eq (car e) key)))
                                collect e)
                    cont)))))

;; Grounding and process-module rules begin with (desig-prop ?designator (:type :a-type)): a
;; call for a designator of another type passes them over without trying them.

(defun type-guard-key (args)
  "The type keyword a guard goal (desig-prop ?d (:type <keyword>)) requires, ARGS being its
arguments after ?d; NIL for any other goal."
  (let ((p (first args)))
    (and (null (rest args)) (consp p) (eq (first p) :type) (consp (rest p)) (null (cddr p))
         (keywordp (second p)) (second p))))

(defun designator-type-key (object)
  "What DESIG-PROP's (:type <keyword>) goals can match in OBJECT: the keyword of its single
\(:type value) entry; NIL when it is no designator or has no keyword type (every such goal
fails); :ALL when it has several type entries or a type that may be a variable."
  (if (typep object 'designator)
      (let ((found :none))
        (dolist (e (description object) (if (eq found :none) nil found))
          (when (and (consp e) (eq (car e) :type) (consp (cdr e)) (null (cddr e)))
            (let ((v (second e)))
              (cond ((not (eq found :none)) (return :all))
                    ((keywordp v) (setf found v))
                    ((and (symbolp v) (is-var v)) (return :all))
                    ;; constants that no keyword unifies with
                    ((typep v '(or symbol string number character cons)) (setf found nil))
                    ;; anything else (a Prolog variable object, ...): every clause is tried
                    (t (return :all)))))))
      nil))

(register-first-goal-guard 'desig-prop #'type-guard-key #'designator-type-key)

(def-fact-group designator-inspection ()
  (<- (designator ?type ?description ?designator)
    (lisp-fun make-designator ?type ?description ?designator))
  (<- (desig-description ?designator ?description)
    (lisp-pred designator-p ?designator)
    (lisp-fun description ?designator ?description))
  (<- (desig-class ?designator ?type)
    (lisp-pred designator-p ?designator)
    (lisp-fun designator-type ?designator ?type))
  (<- (action-desig? ?designator)
    (lisp-pred typep ?designator action-designator))
  (<- (motion-desig? ?designator)
    (lisp-pred typep ?designator motion-designator))
  (<- (loc-desig? ?designator)
    (lisp-pred typep ?designator location-designator))
  (<- (obj-desig? ?designator)
    (lisp-pred typep ?designator object-designator))
  (<- (human-desig? ?designator)
    (lisp-pred typep ?designator human-designator))
  (<- (desig-equal ?designator-1 ?designator-2)
    (lisp-pred desig-equal ?designator-1 ?designator-2))
  (<- (current-designator ?designator ?current)
    (lisp-pred designator-p ?designator)
    (lisp-fun current-desig ?designator ?current))
  (<- (designator-groundings ?designator ?solutions)
    (lisp-pred designator-p ?designator)
    (lisp-fun designator-solutions ?designator ?solutions)))

(defun location-grounding-generator (designator)
  "Location generator: the solutions of the LOCATION-GROUNDING predicate for DESIGNATOR."
  (prolog-solutions designator 'location-grounding))

(register-location-generator 10 location-grounding-generator
  "Solutions of the Prolog predicate LOCATION-GROUNDING, e.g. a (POSE p) property.")

;;; Documentation of the predicates (kept as the function documentation of their symbols).

(loop for (name text) in
      '((action-grounding "Prolog predicate (action-grounding ?designator ?grounding): ground an
action designator to (plan-function resolved-designator) or (plan-function argument...).
Extendable: plan layers add rules per action type.")
        (motion-grounding "Prolog predicate (motion-grounding ?designator ?grounding): ground a
motion designator to a command list (command argument...). Extendable.")
        (location-grounding "Prolog predicate (location-grounding ?designator ?solution): one
candidate location per proof; (POSE p) and (POSES list) are grounded here. Extendable.")
        (desig-prop "Prolog predicate (desig-prop ?designator (?key ?value)): the single-valued
entries of a bound designator; keys are keywords.")
        (designator "The class of all designators; also the Prolog predicate (designator ?type
?description ?designator), which makes a new designator of ?type (e.g. :action) from the
bound ?description, a list of (key value...) entries, as MAKE-DESIGNATOR.")
        (desig-description "Prolog predicate (desig-description ?designator ?description).")
        (desig-class "Prolog predicate (desig-class ?designator ?type): the type keyword.")
        (action-desig? "Prolog predicate (action-desig? ?d): ?d is an action designator.")
        (motion-desig? "Prolog predicate (motion-desig? ?d): ?d is a motion designator.")
        (loc-desig? "Prolog predicate (loc-desig? ?d): ?d is a location designator.")
        (obj-desig? "Prolog predicate (obj-desig? ?d): ?d is an object designator.")
        (human-desig? "Prolog predicate (human-desig? ?d): ?d is a human designator.")
        (current-designator "Prolog predicate (current-designator ?d ?current): the newest
designator of ?d's equation chain.")
        (designator-groundings "Prolog predicate (designator-groundings ?d ?solutions): the lazy
list of all solutions of ?d."))
      do (setf (documentation name 'function) text))
