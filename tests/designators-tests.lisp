;;;; Tests of the designators layer (package DESIG).

(defpackage :cram-designators-tests
  (:use :cl :fiveam))

(in-package :cram-designators-tests)

(def-suite designators :in cram-plans-tests:all
  :description "Designators: construction macros, descriptions, equation chains, grounding.")

(in-suite designators)

(defvar *test-special* :from-special
  "A special variable read by a designator property in the tests.")

;;; Construction macros

(test macro-keywords-and-type
  (let ((d (desig:an action (type picking-up) (arm left))))
    (is (typep d 'desig:action-designator))
    (is (eq :action (desig:designator-type d)))
    (is (eq :an (desig:quantifier d)))
    (is (equal '((:type :picking-up) (:arm :left)) (desig:description d)))))

(test macro-evaluates-question-variables
  (let* ((?arm :right) (?count 3) (?name "bottle-1")
         (d (desig:a motion (type going) (arm ?arm) (count ?count) (name ?name)
                     (literal "text") (speed 0.5))))
    (is (equal '((:type :going) (:arm :right) (:count 3) (:name "bottle-1")
                 (:literal "text") (:speed 0.5))
               (desig:description d)))))

(test macro-nested-designators
  (let* ((d (desig:a location (on (an object (type counter-top) (name kitchen-island)))
                     (for (desig:an object (type bottle)))))
         (on (desig:desig-prop-value d :on))
         (for (desig:desig-prop-value d :for)))
    (is (typep on 'desig:object-designator))
    (is (equal '((:type :counter-top) (:name :kitchen-island)) (desig:description on)))
    (is (typep for 'desig:object-designator))
    (is (eq :bottle (desig:desig-prop-value for :type)))))

(test macro-when-conditional-properties
  (let* ((?grasp nil) (?arm :left)
         (d (desig:an action (type picking-up)
                      (desig:when ?grasp (grasp ?grasp))
                      (when ?arm (arm ?arm) (side ?arm))
                      (object nil))))
    (is (equal '((:type :picking-up) (:arm :left) (:side :left) (:object nil))
               (desig:description d))))
  (let* ((?grasp :front)
         (d (desig:an action (type picking-up) (desig:when ?grasp (grasp ?grasp)))))
    (is (eq :front (desig:desig-prop-value d :grasp)))))

(test macro-lists-quotes-and-specials
  (let* ((?x 2)
         (d (desig:a motion (type moving) (joints (left b ?x)) (raw '(p q))
                     (from-special *test-special*) (pair (1 . 2)))))
    (is (equal '(:left :b 2) (desig:desig-prop-value d :joints)))
    (is (equal '(p q) (desig:desig-prop-value d :raw)))
    (is (eq :from-special (desig:desig-prop-value d :from-special)))
    (is (equal '(1 . 2) (desig:desig-prop-value d :pair)))))

(test macro-all-and-plural
  (let ((d (desig:all objects (type bottle))))
    (is (typep d 'desig:object-designator))
    (is (eq :all (desig:quantifier d)))
    (is (eq :bottle (desig:desig-prop-value d :type)))))

(test macro-expansion-errors
  (signals error (macroexpand-1 '(desig:a location pose)))
  (signals error (macroexpand-1 '(desig:a location (?key 1))))
  (signals error (eval '(desig:a lokation (x 1))))
  (let ((text (handler-case (progn (eval '(desig:a lokation (x 1))) "")
                (error (e) (princ-to-string e)))))
    (is (search "LOKATION" text))))

(test make-designator-normalizes
  (let ((d (desig:make-designator :location '((on "table") (:name "spot") (:pose . 3)))))
    (is (typep d 'desig:location-designator))
    (is (equal '((:on "table") (:name "spot") (:pose 3)) (desig:description d))))
  (signals error (desig:make-designator :nonsense '((:a 1))))
  (signals error (desig:make-designator :action '(not-a-list)))
  (signals error (desig:make-designator :action '(("key" 1))))
  (signals error (desig:make-designator :action '((:a 1) . 5))))

;;; Properties

(test property-access
  (let ((d (desig:make-designator :action '((:type :going) (:pose 1) (:pose 2)))))
    (is (eq :going (desig:desig-prop-value d :type)))
    (is (eq :going (desig:desig-prop-value d 'type)))
    (is (equal '(1 2) (desig:desig-prop-values d :pose)))
    (is (null (desig:desig-prop-value d :missing)))
    (is (null (nth-value 1 (desig:desig-prop-value d :missing))))
    (is (equal (desig:description d) (desig:properties d)))
    (signals error (desig:desig-prop-value 42 :type))))

(test copy-update-extend
  (let* ((d (desig:make-designator :action '((:type :going) (:arm :left) (:speed 1))))
         (copy (desig:copy-designator d :new-description '((:arm :right) (:extra t))))
         (updated (desig:update-designator-properties d '((:speed 2))))
         (extended (desig:extend-designator-properties d '((:arm :right)))))
    (is (equal '((:type :going) (:arm :right) (:speed 1) (:extra t)) (desig:description copy)))
    (is (not (desig:desig-equal d copy)))
    (is (equal '((:type :going) (:arm :left) (:speed 2)) (desig:description updated)))
    (is (equal '(:left :right) (desig:desig-prop-values extended :arm)))
    (is (equal '((:type :going) (:arm :left) (:speed 1)) (desig:description d)))))

;;; Equation chains

(defvar *equate-log* '())

(defmethod desig:on-equate-designators designators-test-log ((successor desig:designator)
                                                             (parent desig:designator))
  (push (cons parent successor) *equate-log*)
  :logged)

(test equate-chains
  (let ((d1 (desig:an object (type bottle)))
        (d2 (desig:an object (type bottle) (name b1)))
        (d3 (desig:an object (type bottle) (name b1) (color red)))
        (other (desig:an object (type cup)))
        (*equate-log* '()))
    (desig:equate d1 d2)
    (desig:equate d1 d3)
    (is (eq d1 (desig:first-desig d3)))
    (is (eq d3 (desig:current-desig d1)))
    (is (eq d2 (desig:parent d3)))
    (is (eq d3 (desig:successor d2)))
    (is (desig:desig-equal d2 d3))
    (is (not (desig:desig-equal d1 other)))
    (is (equal (list d1 d2 d3) (desig:get-equal-designators d2)))
    (is (= 2 (length *equate-log*)))
    (is (eq d3 (cdr (first *equate-log*))))
    (signals error (desig:equate d3 d1))
    (is (null (desig:newest-effective-designator d1)))
    (setf (desig:designator-data d2) :some-data)
    (is (eq d2 (desig:newest-effective-designator d1)))
    (is (eq :some-data (desig:reference d3)))))

(test equate-joins-walked-chains
  ;; the ends of both chains are asked for (from every member) before and after they are
  ;; joined, so that shortcuts remembered before the join must not mislead after it
  (flet ((chain (n type)
           (let ((ds (loop repeat n collect (desig:make-designator :object (list (list :type type))))))
             (loop for (a b) on ds while b do (desig:equate a b))
             ds)))
    (let ((as (chain 5 :cup)) (bs (chain 4 :bowl)))
      (dolist (d as) (is (eq (first as) (desig:first-desig d))) (is (eq (car (last as)) (desig:current-desig d))))
      (dolist (d bs) (is (eq (first bs) (desig:first-desig d))) (is (eq (car (last bs)) (desig:current-desig d))))
      (is (not (desig:desig-equal (third as) (second bs))))
      ;; a middle member of each: B's chain goes behind A's newest
      (desig:equate (second as) (third bs))
      (let ((all (append as bs)))
        (dolist (d all)
          (is (eq (first as) (desig:first-desig d)))
          (is (eq (car (last bs)) (desig:current-desig d)))
          (is (desig:desig-equal d (first all))))
        (is (equal all (desig:get-equal-designators (fourth bs))))
        (is (eq (car (last as)) (desig:parent (first bs))))
        (signals error (desig:equate (first bs) (third as)))
        ;; a third chain behind the joined one, asked from its oldest member
        (let ((c (desig:an object (type :spoon))))
          (desig:equate (first as) c)
          (is (eq c (desig:current-desig (first as))))
          (is (eq (first as) (desig:first-desig c)))
          (is (= 10 (length (desig:get-equal-designators c)))))))
    ;; a chain grown one solution at a time, as NEXT-SOLUTION grows it, stays in order
    (let* ((ds (chain 3000 :plate)))
      (is (eq (first ds) (desig:first-desig (car (last ds)))))
      (is (eq (car (last ds)) (desig:current-desig (first ds))))
      (is (= 3000 (length (desig:get-equal-designators (nth 1500 ds))))))))

;;; Object designators

(test object-reference
  (let ((d (desig:an object (type bottle))))
    (let ((text (handler-case (progn (desig:reference d) "")
                  (desig:designator-error (e)
                    (is (eq d (desig:designator-error-designator e)))
                    (princ-to-string e)))))
      (is (search "BOTTLE" text))
      (is (search "no data" text)))
    (let* ((data (make-instance 'desig:object-designator-data :object-identifier 'bottle-1
                                                              :pose :here))
           (perceived (desig:make-effective-designator d :new-properties '((:name bottle-1))
                                                         :data-object data)))
      (is (desig:effective perceived))
      (desig:equate d perceived)
      (is (eq data (desig:reference d)))
      (is (eq 'bottle-1 (desig:object-identifier d)))
      (is (eq :here (desig:object-pose d))))))

;;; Printing

(test printing
  (let ((d (desig:a motion (type detecting) (object (desig:an object (type bottle))))))
    (is (string= (format nil "#<A MOTION~%    (TYPE DETECTING)~%    (OBJECT #<A OBJECT~%        (TYPE BOTTLE)>)>")
                 (prin1-to-string d))))
  (let ((d (desig:a location (pose "p") (arm (left right)))))
    (is (string= (format nil "#<A LOCATION~%    (POSE \"p\")~%    (ARM (:LEFT :RIGHT))>")
                 (prin1-to-string d)))))
